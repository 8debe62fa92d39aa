//! Instruction-count workload of the crash phase: `icount-crash N` sets up a cycle in
//! PRE-CRASH 5 ms before a predicted contact and runs N cycles from there, the accelerometer
//! delivering the predicted pulse from the contact on (`cycle_benches::ecu_cycle::CrashPhase`):
//! the wake-up and freeze of the prediction (one closed-form solve), the onset-ramp fit, the
//! prediction-matched confirmation with the re-plan from the table, the fire. Run under
//! callgrind for N and N + 1, the difference is the cost of cycle N + 1 alone (e.g.
//! `valgrind --tool=callgrind icount-crash 7` vs `8`). Exits 2 when the crash was not
//! confirmed by the prediction within 20 cycles of N ≥ 20.

use cycle_benches::{ecu_cycle::CrashPhase, icount};

fn main() {
    let n = icount::iterations_from_args();
    let run = || -> anyhow::Result<()> {
        let mut c = CrashPhase::new()?;
        for _ in 0..n {
            c.step();
        }
        if n >= 20 {
            anyhow::ensure!(
                matches!(
                    c.ecu().crash_kind(),
                    Some(restraint::crash::ConfirmKind::Matched(_))
                ),
                "not prediction-matched: {:?}",
                c.ecu().crash_kind()
            );
        }
        Ok(())
    };
    if let Err(e) = run() {
        eprintln!("icount-crash: {e:#}");
        std::process::exit(2);
    }
}
