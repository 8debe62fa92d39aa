//! Restraint optimiser, characteristic-diagram builder and the method's studies.
fn main() {}
