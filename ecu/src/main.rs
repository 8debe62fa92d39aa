//! The fixed-rate restraint ECU process.
fn main() {}
