//! Instruction-count workload: `icount_stage_chain N` runs N cycles of the composed worst-case
//! stage chain (decode both input frames → full collision prediction → LUT lookup → encode and
//! seal three command frames; `cycle_benches::workload::StageChain`). Measured by the budget
//! gate under callgrind at two N; see `cycle_benches::icount`.

use cycle_benches::{icount, workload::StageChain};
use std::hint::black_box;

fn main() {
    let n = icount::iterations_from_args();
    let mut chain = match StageChain::new() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("icount_stage_chain: set-up failed: {e}");
            std::process::exit(2);
        }
    };
    let mut acc = 0.0f64;
    for _ in 0..n {
        let out = black_box(chain.run_once());
        acc += out.delta_v_mps + f64::from(out.airbag_crc);
    }
    println!("{acc}");
}
