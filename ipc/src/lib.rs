//! iceoryx2 zero-copy payload types and service names shared by the bench processes.
