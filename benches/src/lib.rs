//! Criterion benches (benches/benches/) and the per-cycle budget gate.
