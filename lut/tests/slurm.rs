//! The distributed LUT build and Monte-Carlo study on a real scheduler: a one-node Slurm
//! cluster (tests/slurm-cluster.sh: slurmctld + slurmd + munged, job arrays, dependencies).
//!
//! 1. `lut build --grid data/ci-grid.toml --slurm 2` gives a table byte-identical to a local
//!    build (an `SBATCH_TIMELIMIT` of the caller reaches the jobs); running the command again
//!    submits nothing.
//! 2. One array task is killed (scancel) mid-run: the build fails naming that shard; the same
//!    command again recomputes only that shard (the other's file and log stay untouched) and
//!    the result is byte-identical to a local build.
//! 3. The robustness study gives the same result file locally and as a 3-task array.
//!
//! The cluster must start: if it cannot (not root, packages missing and not installable, ports
//! taken), the test fails with the script's output. It never skips.

use lut::table::{self, Grid, GridFile};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

struct Cluster(lut::slurm::OneNodeCluster);

impl Cluster {
    fn start(dir: &Path) -> Cluster {
        let script = workspace().join("tests/slurm-cluster.sh");
        Cluster(lut::slurm::OneNodeCluster::start(&script, dir).unwrap_or_else(|e| panic!("{e:#}")))
    }

    fn lut(&self) -> Command {
        let mut c = Command::new(env!("CARGO_BIN_EXE_lut"));
        c.env("SLURM_CONF", self.0.conf())
            .env_remove("RUST_BACKTRACE");
        c
    }

    fn tool(&self, name: &str, args: &[&str]) -> Output {
        Command::new(name)
            .args(args)
            .env("SLURM_CONF", self.0.conf())
            .output()
            .unwrap_or_else(|e| panic!("cannot run {name}: {e}"))
    }
}

fn text(o: &Output) -> String {
    format!(
        "exit {}\nstdout:\n{}\nstderr:\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Every log of a work directory (for failure messages).
fn logs(work: &Path) -> String {
    let mut s = String::new();
    if let Ok(rd) = std::fs::read_dir(work.join("logs")) {
        let mut paths: Vec<_> = rd.flatten().map(|e| e.path()).collect();
        paths.sort();
        for p in paths {
            s.push_str(&format!(
                "--- {}\n{}\n",
                p.display(),
                std::fs::read_to_string(&p).unwrap_or_default()
            ));
        }
    }
    s
}

fn run_ok(c: &mut Command, work: &Path) -> Output {
    let o = c.output().expect("cannot run lut");
    assert!(o.status.success(), "{}\n{}", text(&o), logs(work));
    o
}

fn local_table(grid: &Grid) -> Vec<u8> {
    table::build_table(grid, Some(2), true)
        .unwrap()
        .0
        .to_bytes()
}

fn state(work: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(work.join("state.json")).unwrap()).unwrap()
}

fn shard_logs(work: &Path, k: u32) -> usize {
    std::fs::read_dir(work.join("logs"))
        .unwrap()
        .flatten()
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with(&format!("shard-{k}."))
        })
        .count()
}

#[test]
fn distributed_build_and_study_on_a_one_node_slurm_cluster() {
    let tmp = std::env::temp_dir().join(format!("lut-slurm-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let t0 = Instant::now();
    let cluster = Cluster::start(&tmp.join("cluster"));
    eprintln!("cluster up in {:.1} s", t0.elapsed().as_secs_f64());

    // 1. The CI grid through Slurm equals the local build, byte for byte.
    let ci_grid = workspace().join("data/ci-grid.toml");
    let out = tmp.join("ci.lut");
    let work = tmp.join("ci.lut.slurm");
    let build = |grid: &Path, out: &Path| {
        let mut c = cluster.lut();
        c.args(["build", "--grid"])
            .arg(grid)
            .arg("--out")
            .arg(out)
            .args([
                "--slurm",
                "2",
                "--cpus-per-task",
                "1",
                "--verify-cells",
                "2",
                "--poll-seconds",
                "0.2",
            ]);
        c
    };
    let t = Instant::now();
    // sbatch's own environment variables pass through (here: a time limit).
    let o = run_ok(
        build(&ci_grid, &out).env("SBATCH_TIMELIMIT", "00:07:00"),
        &work,
    );
    eprintln!("CI grid through Slurm: {:.1} s", t.elapsed().as_secs_f64());
    let array = state(&work)["submissions"][0]["array_job"]
        .as_str()
        .unwrap()
        .to_string();
    let rec = cluster.tool("scontrol", &["-o", "show", "job", &array]);
    assert!(
        String::from_utf8_lossy(&rec.stdout).contains("TimeLimit=00:07:00"),
        "{}",
        text(&rec)
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("shards 2/2 done"), "{err}");
    let local = local_table(&Grid::load(&ci_grid).unwrap());
    assert!(
        std::fs::read(&out).unwrap() == local,
        "the table built through Slurm differs from the local build\n{}",
        logs(&work)
    );
    // The collect job checked the table (checksum, cells, spot re-optimisation).
    assert!(logs(&work).contains("2 cells re-optimised, all within tolerance"));
    // Again: up to date, nothing submitted.
    let before = state(&work);
    let o = run_ok(&mut build(&ci_grid, &out), &work);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("up to date"),
        "{}",
        text(&o)
    );
    assert_eq!(state(&work), before);

    // 2. Kill one array task mid-run; the resume recomputes only that shard. A grid with the CI
    //    grid's axes but more optimiser effort, so that a shard runs for seconds.
    let mut slow = GridFile::load(&ci_grid).unwrap();
    slow.optimiser.particles = 64;
    slow.optimiser.pso_iterations = 80;
    slow.ego.description = "CI grid axes, high optimiser effort (Slurm kill test)".into();
    // With a stated planning margin: the array builds the cells that hold it and the collect
    // job checks every cell against it.
    slow.robust = Some(lut::table::RobustSpec {
        lighter_opponent_kg: 2400.0,
    });
    let slow_grid = tmp.join("slow-grid.toml");
    std::fs::write(&slow_grid, toml::to_string(&slow).unwrap()).unwrap();
    let out = tmp.join("slow.lut");
    let work = tmp.join("slow.lut.slurm");
    let child: Child = build(&slow_grid, &out)
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until shard 2 has finished some cells but not all of them.
    let deadline = Instant::now() + Duration::from_secs(120);
    let victim = loop {
        assert!(
            Instant::now() < deadline,
            "shard 2 never ran\n{}",
            logs(&work)
        );
        let p = std::fs::read_to_string(work.join("progress/2")).unwrap_or_default();
        let v: Vec<usize> = p
            .split_whitespace()
            .filter_map(|x| x.parse().ok())
            .collect();
        if let [done, total] = v[..] {
            assert!(
                done < total,
                "shard 2 finished before it could be killed: the kill test's grid is too fast on this machine"
            );
            if done > 0 {
                let array = state(&work)["submissions"][0]["array_job"]
                    .as_str()
                    .unwrap()
                    .to_string();
                break format!("{array}_2");
            }
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let o = cluster.tool("scancel", &[&victim]);
    assert!(o.status.success(), "{}", text(&o));
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success(),
        "the build did not notice the killed task:\n{err}"
    );
    eprintln!("killed array task {victim}; the build reported:\n{err}");
    assert!(
        err.contains("shard 2/2 (Failed)") && err.contains("CANCELLED"),
        "{err}"
    );
    assert!(!err.contains("shard 1/2"), "{err}");
    assert!(!work.join("shard-2-of-2.bin").exists());
    let shard1 = work.join("shard-1-of-2.bin");
    let shard1_bytes = std::fs::read(&shard1).unwrap();
    let shard1_mtime = std::fs::metadata(&shard1).unwrap().modified().unwrap();
    // Resume: the same command.
    let o = run_ok(&mut build(&slow_grid, &out), &work);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("submitted 1 of 2 shards"), "{err}");
    let st = state(&work);
    assert_eq!(st["submissions"].as_array().unwrap().len(), 2);
    assert_eq!(st["submissions"][1]["tasks"], serde_json::json!([2]));
    assert_eq!(std::fs::read(&shard1).unwrap(), shard1_bytes);
    assert_eq!(
        std::fs::metadata(&shard1).unwrap().modified().unwrap(),
        shard1_mtime
    );
    assert_eq!(
        shard_logs(&work, 1),
        1,
        "shard 1 ran again\n{}",
        logs(&work)
    );
    assert_eq!(shard_logs(&work, 2), 2);
    let t = Instant::now();
    let local = local_table(&Grid::load(&slow_grid).unwrap());
    eprintln!("slow grid locally: {:.1} s", t.elapsed().as_secs_f64());
    assert!(
        std::fs::read(&out).unwrap() == local,
        "the resumed build differs from the local build\n{}",
        logs(&work)
    );
    assert!(
        logs(&work).contains("planning margin of 2400 kg holds in all 24 cells"),
        "{}",
        logs(&work)
    );

    // 3. The robustness study: local and a 3-task array give the same file.
    let study = |out: &Path, slurm: bool| {
        let mut c = cluster.lut();
        c.args(["study", "robustness", "--table"])
            .arg(tmp.join("ci.lut"))
            .args([
                "--closing-speed-kph",
                "74",
                "--opponent-mass-kg",
                "1800",
                "--occupant-mass-kg",
                "75",
                "--seat-mm",
                "300",
                "--samples",
                "3000",
                "--seed",
                "11",
                "--quiet",
                "--out",
            ])
            .arg(out);
        if slurm {
            c.args(["--slurm", "3", "--poll-seconds", "0.2"]);
        }
        c
    };
    let local_json = tmp.join("mc-local.json");
    let slurm_json = tmp.join("mc-slurm.json");
    run_ok(&mut study(&local_json, false), &tmp);
    run_ok(
        &mut study(&slurm_json, true),
        &tmp.join("mc-slurm.json.slurm"),
    );
    let a = std::fs::read_to_string(&local_json).unwrap();
    let b = std::fs::read_to_string(&slurm_json).unwrap();
    assert!(
        a == b,
        "local and Slurm study results differ:\n{a}\n---\n{b}"
    );
    let r = lut::robustness::read_result(&local_json).unwrap();
    assert_eq!(r.study.samples, 3000);
    assert!(r.a_mean_g.sd > 0.0 && r.a_mean_g.min <= r.exact_estimate.a_mean_g);
    // Table shards are not study shards.
    let e = lut::robustness::read_shard("x", &std::fs::read(&shard1).unwrap()).unwrap_err();
    assert!(e.to_string().contains("not a \"robustness\" shard"), "{e}");

    drop(cluster);
    let _ = std::fs::remove_dir_all(&tmp);
    eprintln!("Slurm test: {:.1} s", t0.elapsed().as_secs_f64());
}
