//! End-to-end tests of the real bench processes (see tests/tests/).
