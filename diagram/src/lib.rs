//! Characteristic diagram (restraint LUT): file format and allocation-free multilinear interpolation.
