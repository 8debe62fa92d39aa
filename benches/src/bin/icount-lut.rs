//! Instruction-count workload: `icount-lut N` runs N characteristic-diagram lookups over the
//! bench table and query mix (the same as the `diagram/lookup_varied` criterion bench).
//! Measured by the budget gate under callgrind at two N; see `cycle_benches::icount`.

use cycle_benches::{icount, workload};
use std::hint::black_box;

fn main() {
    let n = icount::iterations_from_args();
    let table = workload::bench_table();
    let view = table.view();
    let qs = workload::bench_queries(1024);
    let mut acc = 0.0f32;
    for i in 0..n {
        if let Some(q) = qs.get((i & 1023) as usize) {
            acc += view.lookup(black_box(q)).values.airbag_level_kn;
        }
    }
    println!("{acc}");
}
