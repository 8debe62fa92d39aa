//! The restraint bench CAN bus: DBC-generated codecs, AUTOSAR-style E2E protection, SocketCAN I/O.
