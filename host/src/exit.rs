//! How a command-line tool ends, one rule for every binary of the bench: exit 0 when it did
//! its work (or its check passed), 1 when a check ran to its end and failed, 2 when an error
//! stopped it — bad input, I/O, a process that could not start. Clap's own argument errors
//! exit 2 as well. The error is one line, `tool: error: …`, with its causes after colons.

use std::fmt;
use std::process::ExitCode;

/// A check that ran to its end and failed (a table whose cells do not verify): exit code 1,
/// where every other error is 2.
#[derive(Debug)]
pub struct CheckFailed(pub String);

impl fmt::Display for CheckFailed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CheckFailed {}

/// The exit code of `tool`'s `result`, the error printed on one line (module docs).
pub fn exit_code(tool: &str, result: anyhow::Result<()>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.chain().any(|c| c.is::<CheckFailed>()) => {
            eprintln!("{tool}: check failed: {e:#}");
            ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("{tool}: error: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// [`exit_code`] for a tool whose run is a check (`Ok(false)`: it ran and failed, exit 1).
pub fn check_exit_code(tool: &str, result: anyhow::Result<bool>) -> ExitCode {
    match result {
        Ok(false) => ExitCode::from(1),
        r => exit_code(tool, r.map(|_| ())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    #[test]
    fn a_failed_check_is_1_and_any_other_error_2_with_its_causes() {
        assert_eq!(exit_code("t", Ok(())), ExitCode::SUCCESS);
        let check = Err(CheckFailed("3 of 9 cells do not match".into())).context("verify x.lut");
        assert_eq!(exit_code("t", check), ExitCode::from(1));
        let io: anyhow::Result<()> =
            Err(std::io::Error::from(std::io::ErrorKind::NotFound)).context("/nonexistent");
        assert_eq!(exit_code("t", io), ExitCode::from(2));
        assert_eq!(check_exit_code("t", Ok(true)), ExitCode::SUCCESS);
        assert_eq!(check_exit_code("t", Ok(false)), ExitCode::from(1));
        assert_eq!(
            check_exit_code("t", Err(anyhow::anyhow!("x"))),
            ExitCode::from(2)
        );
    }
}
