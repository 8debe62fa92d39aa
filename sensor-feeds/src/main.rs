//! Scenario player: object, vehicle, occupant and crash-accelerometer feeds.
fn main() {}
