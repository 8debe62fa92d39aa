//! `misuse-matrix --slurm N` on a real scheduler: a one-node Slurm cluster
//! (`tests/slurm-cluster.sh`, `lut::slurm::OneNodeCluster`) runs the matrix as a job array and
//! the table it prints is the local run's, row for row; run again, it resubmits only the
//! tasks without a whole outcomes file. The cluster must start: if it cannot
//! (not root, packages missing and not installable), the test fails with the script's output.
//! It never skips.

use std::process::{Command, Output};

fn matrix() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_misuse-matrix"));
    c.args(["--variants", "640", "--seed", "4", "--quiet"])
        .env_remove("RUST_BACKTRACE");
    c
}

/// The table without its timing line (the only line that depends on where it ran).
fn table(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter(|l| !l.contains(" variants in "))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn the_matrix_on_a_slurm_job_array_prints_the_local_table() {
    let tmp = std::env::temp_dir().join(format!("matrix-slurm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let cluster = lut::slurm::OneNodeCluster::start(
        &e2e_tests::repo_root().join("tests/slurm-cluster.sh"),
        &tmp.join("cluster"),
    )
    .unwrap_or_else(|e| panic!("{e:#}"));
    let local = matrix().output().expect("misuse-matrix");
    let work = tmp.join("work");
    let distributed = matrix()
        .args(["--slurm", "3", "--cpus-per-task", "1", "--work-dir"])
        .arg(&work)
        .env("SLURM_CONF", cluster.conf())
        .output()
        .expect("misuse-matrix --slurm");
    let logs: String = (0..3)
        .map(|k| {
            std::fs::read_to_string(work.join(format!("logs/shard-{k}.log"))).unwrap_or_default()
        })
        .collect();
    assert_eq!(
        local.status.code(),
        distributed.status.code(),
        "{}\n{logs}",
        String::from_utf8_lossy(&distributed.stderr)
    );
    let (a, b) = (table(&local), table(&distributed));
    assert!(a.lines().count() > 30, "{a}");
    assert_eq!(
        a,
        b,
        "\n{}\n{logs}",
        String::from_utf8_lossy(&distributed.stderr)
    );
    // Three tasks, each with its own outcomes.
    for k in 0..3 {
        assert!(
            work.join(format!("shard-{k}.json")).exists(),
            "task {k}\n{logs}"
        );
    }
    // The same command again resumes: one task's file lost, one cut
    // short → only those two are submitted, and the table is the same.
    std::fs::remove_file(work.join("shard-1.json")).unwrap();
    std::fs::write(work.join("shard-2.json"), "[{\"family\": 0").unwrap();
    let again = || {
        matrix()
            .args(["--slurm", "3", "--cpus-per-task", "1", "--work-dir"])
            .arg(&work)
            .env("SLURM_CONF", cluster.conf())
            .output()
            .expect("misuse-matrix --slurm")
    };
    let resumed = again();
    let said = String::from_utf8_lossy(&resumed.stderr);
    assert!(said.contains("tasks 1,2 of 3 (1 already done)"), "{said}");
    assert_eq!(a, table(&resumed), "{said}");
    // Everything done: nothing is submitted.
    let done = again();
    let said = String::from_utf8_lossy(&done.stderr);
    assert!(said.contains("all 3 tasks already done"), "{said}");
    assert_eq!(a, table(&done), "{said}");
    // Other arguments start afresh.
    let other = matrix()
        .args([
            "--family",
            "pothole",
            "--slurm",
            "3",
            "--cpus-per-task",
            "1",
            "--work-dir",
        ])
        .arg(&work)
        .env("SLURM_CONF", cluster.conf())
        .output()
        .expect("misuse-matrix --slurm");
    let said = String::from_utf8_lossy(&other.stderr);
    assert!(said.contains("tasks 0,1,2 of 3 (0 already done)"), "{said}");
    drop(cluster);
    let _ = std::fs::remove_dir_all(&tmp);
}
