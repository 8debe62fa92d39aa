//! Instruction-count workload: `icount-cycle N` runs N worst-case pre-crash cycles of the real
//! ECU (`restraint::RestraintCycle::step` with a new object sample every cycle: track filter +
//! LUT + state machine + command encode), set up by
//! `cycle_benches::ecu_cycle::WorstCasePreCrash` exactly as the `cycle/full_precrash_worst_case`
//! criterion bench. Measured by the budget gate under callgrind at two N; exits 2 when the
//! run did not stay on the worst-case path (then the count would measure something else).

use cycle_benches::{ecu_cycle::WorstCasePreCrash, icount};

fn main() {
    let n = icount::iterations_from_args();
    let run = || -> anyhow::Result<u64> {
        let mut w = WorstCasePreCrash::new()?;
        for _ in 0..n {
            w.step();
        }
        w.verify()?;
        Ok(w.frames_sent())
    };
    match run() {
        Ok(sent) => println!("{sent}"),
        Err(e) => {
            eprintln!("icount-cycle: {e:#}");
            std::process::exit(2);
        }
    }
}
