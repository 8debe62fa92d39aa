//! Belt retractor and airbag module stubs: validate, log, act on and judge commands.
fn main() {}
