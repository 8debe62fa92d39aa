//! Real-time process settings. Each one is optional; when the OS refuses, the ECU keeps
//! running without it and says so (message on stderr and in the report), because a
//! bench without RT privileges is still useful — only its timing tails get worse.

use std::fs::File;
use std::io::Write;

use nix::sched::{sched_setaffinity, CpuSet};
use nix::sys::mman::{mlockall, MlockAllFlags};
use nix::unistd::Pid;
use serde::Serialize;

use super::config::RtConfig;

/// Outcome of one RT setting.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SettingOutcome {
    /// Asked for by config/flag.
    pub requested: bool,
    /// Actually in effect.
    pub granted: bool,
    /// Human-readable detail (why not, or what was set).
    pub detail: String,
}

impl SettingOutcome {
    fn off() -> Self {
        Self {
            requested: false,
            granted: false,
            detail: "not requested".into(),
        }
    }
    fn ok(detail: impl Into<String>) -> Self {
        Self {
            requested: true,
            granted: true,
            detail: detail.into(),
        }
    }
    fn denied(detail: impl Into<String>) -> Self {
        Self {
            requested: true,
            granted: false,
            detail: detail.into(),
        }
    }
}

/// Scheduling outcome (policy actually in effect).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SchedOutcome {
    /// Requested/granted/detail.
    #[serde(flatten)]
    pub outcome: SettingOutcome,
    /// `SCHED_FIFO` or `SCHED_OTHER`.
    pub policy: &'static str,
    /// FIFO priority when granted.
    pub priority: Option<u8>,
}

/// All RT settings in effect. Holding this keeps the PM-QoS request alive.
#[derive(Debug, Serialize)]
pub struct RtState {
    /// SCHED_FIFO.
    pub sched: SchedOutcome,
    /// mlockall.
    pub mlockall: SettingOutcome,
    /// CPU pinning.
    pub cpu_affinity: SettingOutcome,
    /// PM-QoS.
    pub pm_qos: SettingOutcome,
    /// Stack pre-faulted, KiB.
    pub prefault_stack_kib: usize,
    #[serde(skip)]
    pm_qos_fd: Option<File>,
}

impl RtState {
    /// Whether the PM-QoS file descriptor is held open.
    pub fn holds_pm_qos(&self) -> bool {
        self.pm_qos_fd.is_some()
    }

    /// One-line-per-setting summary.
    pub fn summary_lines(&self) -> Vec<String> {
        let line = |name: &str, o: &SettingOutcome| {
            let state = match (o.requested, o.granted) {
                (false, _) => "off",
                (true, true) => "ON",
                (true, false) => "DENIED",
            };
            format!("{name:<12} {state:<6} {}", o.detail)
        };
        vec![
            line("sched", &self.sched.outcome),
            line("mlockall", &self.mlockall),
            line("cpu pinning", &self.cpu_affinity),
            line("pm-qos", &self.pm_qos),
        ]
    }
}

/// Applies the requested settings in a safe order (pin, lock, pre-fault, PM-QoS, and
/// SCHED_FIFO last so set-up work does not run at RT priority). Never fails.
pub fn apply(cfg: &RtConfig) -> RtState {
    let cpu_affinity = match cfg.cpu {
        None => SettingOutcome::off(),
        Some(cpu) => pin_to_cpu(cpu),
    };
    let mlock = if cfg.mlockall {
        match mlockall(MlockAllFlags::MCL_CURRENT | MlockAllFlags::MCL_FUTURE) {
            Ok(()) => SettingOutcome::ok("all current and future pages locked"),
            Err(e) => SettingOutcome::denied(format!(
                "mlockall failed ({e}); needs CAP_IPC_LOCK or `ulimit -l unlimited` — page faults may add latency"
            )),
        }
    } else {
        SettingOutcome::off()
    };
    prefault_stack(cfg.prefault_stack_kib);
    let (pm_qos, pm_qos_fd) = if cfg.pm_qos {
        hold_cpu_dma_latency_zero()
    } else {
        (SettingOutcome::off(), None)
    };
    let sched = match cfg.sched_fifo_priority {
        None => SchedOutcome {
            outcome: SettingOutcome::off(),
            policy: "SCHED_OTHER",
            priority: None,
        },
        Some(prio) => set_fifo(prio),
    };
    RtState {
        sched,
        mlockall: mlock,
        cpu_affinity,
        pm_qos,
        prefault_stack_kib: cfg.prefault_stack_kib,
        pm_qos_fd,
    }
}

fn pin_to_cpu(cpu: usize) -> SettingOutcome {
    let mut set = CpuSet::new();
    if let Err(e) = set.set(cpu) {
        return SettingOutcome::denied(format!("CPU {cpu} cannot be represented ({e})"));
    }
    match sched_setaffinity(Pid::from_raw(0), &set) {
        Ok(()) => SettingOutcome::ok(format!("pinned to CPU {cpu}")),
        Err(e) => SettingOutcome::denied(format!(
            "sched_setaffinity(CPU {cpu}) failed ({e}); CPU offline or outside the allowed set"
        )),
    }
}

fn set_fifo(prio: u8) -> SchedOutcome {
    let param = nix::libc::sched_param {
        sched_priority: i32::from(prio),
    };
    // SAFETY: plain syscall on the calling process with a valid, initialised parameter.
    let rc = unsafe { nix::libc::sched_setscheduler(0, nix::libc::SCHED_FIFO, &param) };
    if rc == 0 {
        SchedOutcome {
            outcome: SettingOutcome::ok(format!("SCHED_FIFO priority {prio}")),
            policy: "SCHED_FIFO",
            priority: Some(prio),
        }
    } else {
        let err = nix::errno::Errno::last();
        SchedOutcome {
            outcome: SettingOutcome::denied(format!(
                "SCHED_FIFO {prio} refused ({err}); needs CAP_SYS_NICE or an rtprio limit — running SCHED_OTHER"
            )),
            policy: "SCHED_OTHER",
            priority: None,
        }
    }
}

const CPU_DMA_LATENCY: &str = "/dev/cpu_dma_latency";

fn hold_cpu_dma_latency_zero() -> (SettingOutcome, Option<File>) {
    // The kernel keeps the request only while the file stays open, so we hold the fd.
    match File::options().write(true).open(CPU_DMA_LATENCY) {
        Ok(mut f) => match f.write_all(&0i32.to_ne_bytes()) {
            Ok(()) => (
                SettingOutcome::ok(format!("{CPU_DMA_LATENCY} held at 0 µs")),
                Some(f),
            ),
            Err(e) => (
                SettingOutcome::denied(format!("write to {CPU_DMA_LATENCY} failed ({e})")),
                None,
            ),
        },
        Err(e) => (
            SettingOutcome::denied(format!(
                "cannot open {CPU_DMA_LATENCY} ({e}); needs root or write access — deep C-states may add wake-up latency"
            )),
            None,
        ),
    }
}

/// Touches `kib` KiB of stack so the pages are mapped (and locked under mlockall)
/// before the loop: a first-touch page fault inside a cycle costs microseconds.
pub fn prefault_stack(kib: usize) {
    const CHUNK: usize = 16 * 1024;
    #[inline(never)]
    fn touch(chunks_left: usize) {
        let mut buf = [0u8; CHUNK];
        std::hint::black_box(&mut buf);
        if chunks_left > 1 {
            touch(chunks_left - 1);
        }
        std::hint::black_box(&buf);
    }
    let chunks = (kib * 1024).div_ceil(CHUNK);
    if chunks > 0 {
        touch(chunks);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_requested_means_nothing_granted() {
        let s = apply(&RtConfig {
            prefault_stack_kib: 64,
            ..RtConfig::default()
        });
        assert!(!s.sched.outcome.requested && !s.sched.outcome.granted);
        assert_eq!(s.sched.policy, "SCHED_OTHER");
        assert!(!s.mlockall.requested && !s.pm_qos.requested && !s.cpu_affinity.requested);
        assert!(!s.holds_pm_qos());
    }

    #[test]
    fn requests_are_reported_granted_or_denied_never_panic() {
        let s = apply(&RtConfig {
            sched_fifo_priority: None, // FIFO is not tried in unit tests: it would stick.
            mlockall: false,
            cpu: Some(0),
            pm_qos: true,
            prefault_stack_kib: 16,
        });
        assert!(
            s.cpu_affinity.requested && s.cpu_affinity.granted,
            "{:?}",
            s.cpu_affinity
        );
        assert!(s.pm_qos.requested);
        assert_eq!(s.pm_qos.granted, s.holds_pm_qos());
        assert!(!s.pm_qos.detail.is_empty());
    }

    #[test]
    fn impossible_cpu_is_denied_with_message() {
        let o = pin_to_cpu(100_000);
        assert!(o.requested && !o.granted);
        assert!(o.detail.contains("100000"), "{}", o.detail);
    }
}
