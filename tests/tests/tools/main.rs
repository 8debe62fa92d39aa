//! The offline tools' tests — offline-bench, misuse-matrix (and its Slurm run), the command-line
//! conventions every tool shares, the docs check — in one test binary: each test binary of
//! this package links the whole bench (iceoryx2, SocketCAN, plotters …), 30–60 s of the suite's
//! build apiece, and these four need nothing of their own.

mod bus_encode;
mod commits;
mod docs_check;
mod matrix_cli;
mod matrix_slurm;
mod offline;
mod one_build;
mod recording;
mod replay;
mod schema_versions;

/// Runs the binary `exe` with `args`: its exit code (−1 when killed), stdout and stderr.
fn run_tool(exe: &str, args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(exe)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{exe} does not run: {e}"));
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
