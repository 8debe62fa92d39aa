//! The offline tools' tests — offline-bench, misuse-matrix (and its Slurm run), the command-line
//! conventions every tool shares, the docs check — in one test binary: each test binary of
//! this package links the whole bench (iceoryx2, SocketCAN, plotters …), 30–60 s of the suite's
//! build apiece, and these four need nothing of their own.

mod bus_encode;
mod docs_check;
mod matrix_cli;
mod matrix_slurm;
mod offline;
mod one_build;
mod recording;
