//! Crash-pulse and occupant physics of the situation-adaptive restraint method (no_std core).
