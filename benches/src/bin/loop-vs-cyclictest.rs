//! Loop timing harness: the ECU loop's wake-up latency against `cyclictest` (rt-tests), same
//! machine, same session, same period, policy, priority, CPU, memory locking, PM-QoS and count.
//!
//! `target/release/loop-vs-cyclictest --cycles 20000 --period-us 1000 [--sched-fifo 80]
//! [--cpu 1] [--out DIR] [--plot FILE]` (the ECU is the `ecu` built beside it; the PNG and the
//! raw data go to `--out`, never over the committed docs/img picture unless `--plot` says so).
//!
//! cyclictest measures the OS floor: a thread that does nothing but sleep to an absolute
//! deadline (clock_nanosleep TIMER_ABSTIME) and read the clock. The ECU loop does the same plus
//! its cycle; if its wake-up latency distribution matches cyclictest's, the loop adds nothing
//! measurable over the OS. Prints both side by side and plots both into one PNG. It never
//! fails on the numbers (wall-clock tails on a shared VM are reported, not gated).

use anyhow::{bail, Context};
use clap::Parser;
use cycle_benches::latency::{CyclictestHistogram, EcuReport, PercentilesUs};
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::process::Command;

#[derive(Parser, Debug)]
#[command(
    name = "loop-vs-cyclictest",
    version,
    about = "ECU loop wake-up latency vs cyclictest, same settings, one session"
)]
struct Args {
    /// Cycles (ECU) = loops (cyclictest).
    #[arg(long, default_value_t = 20_000)]
    cycles: u64,
    /// Period, µs.
    #[arg(long, default_value_t = 1000)]
    period_us: u64,
    /// SCHED_FIFO priority for both (absent: SCHED_OTHER for both); as `ecu --sched-fifo`.
    #[arg(long = "sched-fifo", alias = "fifo", value_name = "PRIO")]
    fifo: Option<u8>,
    /// Pin both to this CPU.
    #[arg(long)]
    cpu: Option<usize>,
    /// Do not mlockall (default: both lock memory); as `ecu --no-mlockall`.
    #[arg(long = "no-mlockall", alias = "no-mlock")]
    no_mlock: bool,
    /// Do not hold /dev/cpu_dma_latency at 0 (cyclictest `--laptop`, ECU `--no-pm-qos`).
    #[arg(long)]
    no_pm_qos: bool,
    /// cyclictest histogram range, µs (samples above are counted as overflows).
    #[arg(long, default_value_t = 10_000)]
    hist_max_us: u64,
    /// Output PNG (default: timing-loop-vs-cyclictest.png in --out).
    #[arg(long = "plot", alias = "png", value_name = "FILE")]
    png: Option<PathBuf>,
    /// Folder for the plot, the raw cyclictest histogram and the ECU report JSON.
    #[arg(
        long = "out",
        alias = "out-dir",
        value_name = "DIR",
        default_value = "target/loop-vs-cyclictest"
    )]
    out_dir: PathBuf,
    /// ECU binary (default: the `ecu` beside this binary, as `cargo build --release
    /// --workspace` leaves it).
    #[arg(long, value_name = "FILE")]
    ecu: Option<PathBuf>,
}

fn main() {
    if let Err(e) = run() {
        eprintln!("loop-vs-cyclictest: error: {e:#}");
        std::process::exit(2);
    }
}

fn run() -> anyhow::Result<()> {
    let a = Args::parse();
    std::fs::create_dir_all(&a.out_dir)?;
    let png = a
        .png
        .clone()
        .unwrap_or_else(|| a.out_dir.join("timing-loop-vs-cyclictest.png"));
    let ecu = match &a.ecu {
        Some(p) => p.clone(),
        None => std::env::current_exe()?.with_file_name("ecu"),
    };
    anyhow::ensure!(
        ecu.is_file(),
        "no ECU binary at {} (build it: cargo build --release -p ecu; or pass --ecu FILE)",
        ecu.display()
    );

    // --- cyclictest ---------------------------------------------------------------------
    let histfile = a.out_dir.join("cyclictest-hist.txt");
    // rt-tests 2.x: clock_nanosleep with an absolute deadline is the default (the old `-n`
    // flag is gone); `-t1` one thread; `-q` summary only.
    let _ = std::fs::remove_file(&histfile);
    let mut ct = Command::new("cyclictest");
    ct.args(["-t1", "-q"])
        .arg(format!("-i{}", a.period_us))
        .arg(format!("-l{}", a.cycles))
        .arg(format!("-h{}", a.hist_max_us))
        .arg(format!("--histfile={}", histfile.display()));
    ct.arg(format!("-p{}", a.fifo.unwrap_or(0)));
    if let Some(c) = a.cpu {
        ct.arg(format!("-a{c}"));
    }
    if !a.no_mlock {
        ct.arg("-m");
    }
    if a.no_pm_qos {
        ct.arg("--laptop");
    }
    eprintln!("loop-vs-cyclictest: {ct:?}");
    let out = ct
        .output()
        .context("cannot start cyclictest (Debian: apt-get install rt-tests)")?;
    if !out.status.success() {
        bail!(
            "cyclictest failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let ct_hist = CyclictestHistogram::parse(&std::fs::read_to_string(&histfile)?)
        .with_context(|| format!("parsing {}", histfile.display()))?;
    let ct_p = ct_hist.percentiles();

    // --- ECU ------------------------------------------------------------------------------
    let report_path = a.out_dir.join("ecu-report.json");
    let mut ec = Command::new(&ecu);
    ec.args(["--no-can", "--quiet"])
        .arg("--cycles")
        .arg(a.cycles.to_string())
        .arg("--period-us")
        .arg(a.period_us.to_string())
        .arg("--json")
        .arg(&report_path)
        .arg("--service-prefix")
        .arg(format!("loop-vs-cyclictest-{}", std::process::id()));
    if let Some(p) = a.fifo {
        ec.arg("--sched-fifo").arg(p.to_string());
    }
    if let Some(c) = a.cpu {
        ec.arg("--cpu").arg(c.to_string());
    }
    ec.arg(if a.no_mlock {
        "--no-mlockall"
    } else {
        "--mlockall"
    });
    ec.arg(if a.no_pm_qos {
        "--no-pm-qos"
    } else {
        "--pm-qos"
    });
    eprintln!("loop-vs-cyclictest: {ec:?}");
    let out = ec
        .output()
        .with_context(|| format!("cannot start {}", ecu.display()))?;
    if !out.status.success() {
        bail!("ecu failed: {}", String::from_utf8_lossy(&out.stderr));
    }
    let report: EcuReport = serde_json::from_str(&std::fs::read_to_string(&report_path)?)
        .with_context(|| format!("parsing {}", report_path.display()))?;

    print!("{}", side_by_side(&a, &ct_hist, &ct_p, &report));
    plot(&png, &ct_hist, &ct_p, &report, a.cycles)?;
    println!("plot: {}", png.display());
    println!("raw: {} and {}", histfile.display(), report_path.display());
    Ok(())
}

fn ratio(e: f64, c: f64) -> String {
    if c > 0.0 {
        format!("{:.2}", e / c)
    } else {
        "-".to_owned()
    }
}

fn side_by_side(a: &Args, h: &CyclictestHistogram, c: &PercentilesUs, r: &EcuReport) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "\nwake-up latency, {} cycles at {} µs, policy {}, cpu {}, mlockall {}, pm-qos {}\n",
        a.cycles,
        a.period_us,
        a.fifo
            .map_or_else(|| "SCHED_OTHER".to_owned(), |p| format!("SCHED_FIFO {p}")),
        a.cpu.map_or_else(|| "any".to_owned(), |c| c.to_string()),
        !a.no_mlock,
        !a.no_pm_qos
    ));
    s.push_str(&format!(
        "{:<10} {:>14} {:>14} {:>12} {:>14}\n",
        "", "cyclictest µs", "ECU wake µs", "ECU/cyclic", "ECU exec µs"
    ));
    let row = |name: &str, cv: f64, ev: f64, ex: f64| {
        format!(
            "{name:<10} {cv:>14.1} {ev:>14.1} {:>12} {ex:>14.2}\n",
            ratio(ev, cv)
        )
    };
    s.push_str(&row("p50", c.p50, r.wake_latency_us.p50, r.exec_us.p50));
    s.push_str(&row("p99", c.p99, r.wake_latency_us.p99, r.exec_us.p99));
    s.push_str(&row(
        "p99.9",
        c.p999,
        r.wake_latency_us.p999,
        r.exec_us.p999,
    ));
    s.push_str(&row("max", c.max, r.wake_latency_us.max, r.exec_us.max));
    s.push_str(&format!(
        "cyclictest: min {:.0} µs, avg {:.0} µs, {} samples, {} above {} µs (1 µs buckets; \
         percentiles are bucket upper edges)\n",
        h.min_us,
        h.avg_us,
        h.total(),
        h.overflows,
        h.counts.len().saturating_sub(1)
    ));
    s.push_str(&format!(
        "ECU: activity `{}`, {} cycles, {} overruns, sched {}, CAN: {}\n",
        r.activity,
        r.cycles,
        r.overruns,
        r.rt.get("sched")
            .map_or_else(String::new, |v| v.to_string()),
        r.can.get("reason").and_then(|v| v.as_str()).unwrap_or("?")
    ));
    s.push_str(
        "note: the ECU's CAN side was switched off (--no-can; this host has no SocketCAN), \
         so the ECU cycle did no CAN I/O.\n",
    );
    s
}

/// Two panels on the same log-spaced buckets (10 per decade): the wake-up latency histograms
/// of cyclictest (its 1 µs buckets re-binned) and of the ECU loop (the report's
/// `wake_latency_hist_us`), as fractions of samples; and the exceedance curves P(latency > x)
/// of both with the ECU's p50/p99/p99.9/max as points. An ECU report without buckets (older
/// binary) is drawn as percentile lines only.
fn plot(
    png: &Path,
    h: &CyclictestHistogram,
    c: &PercentilesUs,
    r: &EcuReport,
    cycles: u64,
) -> anyhow::Result<()> {
    if let Some(dir) = png.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let root = BitMapBackend::new(png, (1000, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(430);
    let x_max = (c.max.max(r.wake_latency_us.max) * 1.5).max(10.0);
    let floor = 0.5 / cycles.max(1) as f64;

    let ct_buckets = h.log_buckets();
    let ct_total = h.total().max(1) as f64;
    let step = 10f64.powf(0.1);
    let ecu_total = r
        .wake_latency_hist_us
        .iter()
        .map(|b| b.1)
        .sum::<u64>()
        .max(1) as f64;
    let mut ch = ChartBuilder::on(&top)
        .caption(
            "wake-up latency histograms (10 log buckets per decade, fraction of samples)",
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((1f64..x_max).log_scale(), (floor..1.0f64).log_scale())?;
    ch.configure_mesh()
        .x_desc("wake-up latency, µs")
        .y_desc("fraction of samples")
        .draw()?;
    ch.draw_series(ct_buckets.iter().filter(|b| b.2 > 0).map(|&(lo, hi, n)| {
        Rectangle::new(
            [(lo.max(1.0), floor), (hi, n as f64 / ct_total)],
            BLUE.mix(0.45).filled(),
        )
    }))?
    .label(format!("cyclictest ({} samples)", h.total()))
    .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], BLUE.mix(0.45).filled()));
    if r.wake_latency_hist_us.is_empty() {
        for (name, v, col) in [
            ("ECU p50", r.wake_latency_us.p50, RED),
            ("ECU p99", r.wake_latency_us.p99, MAGENTA),
            ("ECU p99.9", r.wake_latency_us.p999, GREEN),
            ("ECU max", r.wake_latency_us.max, BLACK),
        ] {
            let v = v.max(1.0);
            ch.draw_series(LineSeries::new(
                vec![(v, floor), (v, 1.0)],
                col.stroke_width(2),
            ))?
            .label(format!("{name} {v:.1} µs"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], col.stroke_width(2)));
        }
    } else {
        ch.draw_series(
            r.wake_latency_hist_us
                .iter()
                .filter(|b| b.1 > 0)
                .map(|&(hi, n)| {
                    Rectangle::new(
                        [((hi / step).max(1.0), floor), (hi, n as f64 / ecu_total)],
                        RED.stroke_width(2),
                    )
                }),
        )?
        .label(format!("ECU loop ({} cycles)", r.cycles))
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], RED.stroke_width(2)));
    }
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;

    let total = h.total().max(1) as f64;
    let mut ch = ChartBuilder::on(&bottom)
        .caption(
            "exceedance P(latency > x): cyclictest vs ECU loop",
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((1f64..x_max).log_scale(), (floor..1.0f64).log_scale())?;
    ch.configure_mesh()
        .x_desc("wake-up latency, µs")
        .y_desc("fraction of cycles above")
        .draw()?;
    let mut above = total;
    let mut pts = Vec::new();
    for (us, &n) in h.counts.iter().enumerate() {
        above -= n as f64;
        if above > 0.0 {
            pts.push((((us + 1) as f64).max(1.0), above / total));
        }
    }
    if h.overflows > 0 {
        pts.push((h.max_us.max(1.0), 1.0 / total));
    }
    ch.draw_series(LineSeries::new(pts, BLUE.stroke_width(2)))?
        .label("cyclictest")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], BLUE.stroke_width(2)));
    if !r.wake_latency_hist_us.is_empty() {
        let mut above = ecu_total;
        let mut pts = Vec::new();
        for &(hi, n) in &r.wake_latency_hist_us {
            above -= n as f64;
            if above > 0.0 {
                pts.push((hi.max(1.0), above / ecu_total));
            }
        }
        ch.draw_series(LineSeries::new(pts, RED.stroke_width(2)))?
            .label("ECU loop (log buckets)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], RED.stroke_width(2)));
    }
    let ecu_pts = [
        (r.wake_latency_us.p50, 0.5),
        (r.wake_latency_us.p99, 0.01),
        (r.wake_latency_us.p999, 0.001),
        (r.wake_latency_us.max, 1.0 / cycles.max(1) as f64),
    ];
    ch.draw_series(
        ecu_pts
            .iter()
            .map(|&(x, y)| Circle::new((x.max(1.0), y), 6, RED.filled())),
    )?
    .label("ECU loop (p50, p99, p99.9, max)")
    .legend(|(x, y)| Circle::new((x + 7, y), 5, RED.filled()));
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    root.present()?;
    Ok(())
}
