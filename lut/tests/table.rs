//! End-to-end characteristic-diagram build on the small CI grid: build → rebuild is
//! byte-identical → shards merged equal the full build → verify → inspect (the binary).

use diagram::Diagram;
use lut::progress::Progress;
use lut::table::{self, Grid};
use lut::verify;
use std::path::PathBuf;
use std::process::Command;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lut-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn ci_grid_end_to_end() {
    let grid = Grid::load(workspace().join("data/ci-grid.toml")).unwrap();
    let (full, stats) = table::build_table(&grid, Some(2), true).unwrap();
    assert_eq!(stats.cells, grid.axes.cell_count());
    let bytes = full.to_bytes();

    // Rerun with another thread count: byte-identical.
    let (again, _) = table::build_table(&grid, Some(1), true).unwrap();
    assert_eq!(again.to_bytes(), bytes, "rebuild is not byte-identical");

    // Shards (merged out of order) equal the full build.
    let n = 3;
    let quiet = Progress::new(0, "", "cells", true);
    let mut shards: Vec<_> = (1..=n)
        .map(|k| table::build_shard(&grid, k, n, Some(1), &quiet).unwrap().0)
        .collect();
    shards.reverse();
    let shard_bytes: Vec<Vec<u8>> = shards.iter().map(|s| s.to_bytes().unwrap()).collect();
    let decoded: Vec<_> = shard_bytes
        .iter()
        .enumerate()
        .map(|(i, b)| (format!("s{i}"), table::read_shard("t", b).unwrap()))
        .collect();
    let merged = table::merge_shards(&decoded, Some(&grid.identity().unwrap())).unwrap();
    assert_eq!(
        merged.to_bytes(),
        bytes,
        "merged shards differ from the full build"
    );
    // A missing shard is an error naming the gap, not a silently smaller table.
    let e = table::merge_shards(&decoded[..2], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("items 0..8 missing"), "{e}");
    // A shard of another grid (other seed) is refused, naming the file.
    let mut other = grid.clone();
    other.optimiser.seed += 1;
    let foreign = table::build_shard(&other, 1, n, Some(1), &quiet).unwrap().0;
    let mut mixed = decoded[..2].to_vec();
    mixed.push(("foreign.bin".into(), foreign));
    let e = table::merge_shards(&mixed, None).unwrap_err().to_string();
    assert!(e.starts_with("foreign.bin: shard of another grid"), "{e}");
    // A corrupt shard file is refused, naming the file and the reason.
    let mut bad = shard_bytes[0].clone();
    let mid = bad.len() / 2;
    bad[mid] ^= 1;
    let e = table::read_shard("dir/shard-3-of-3.bin", &bad)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("dir/shard-3-of-3.bin: corrupt shard file: checksum mismatch"),
        "{e}"
    );

    // Every cell's optimum lies inside the hardware bounds and its prediction is self-consistent.
    for c in full.cells() {
        assert!(
            (1.0..=12.0).contains(&c.belt_limiter_kn) && (0.0..=12.0).contains(&c.airbag_level_kn)
        );
        assert!(
            (-100.0..=20.0).contains(&c.pretensioner_time_ms)
                && (3.0..=40.0).contains(&c.airbag_time_ms)
        );
        assert!(c.a_max_g >= c.a_mean_g);
    }

    // Save, then verify and inspect through the binary.
    let path = tmp("ci.lut");
    full.save(&path).unwrap();
    assert_eq!(Diagram::load(&path).unwrap().to_bytes(), bytes);
    let exe = env!("CARGO_BIN_EXE_lut");
    let out = Command::new(exe)
        .args([
            "verify",
            path.to_str().unwrap(),
            "--cells",
            "6",
            "--seed",
            "3",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "verify failed: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let out = Command::new(exe)
        .args(["inspect", path.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("closing_speed_kph") && text.contains("bottoming-out"),
        "{text}"
    );

    // A corrupted table makes verify fail with a message naming the file.
    let mut bad = bytes.clone();
    let last = bad.len() - 3;
    bad[last] ^= 0x40;
    let bad_path = tmp("bad.lut");
    std::fs::write(&bad_path, &bad).unwrap();
    // RUST_BACKTRACE set (as on many developer machines): still one readable line, no dump.
    let out = Command::new(exe)
        .args(["verify", bad_path.to_str().unwrap()])
        .env("RUST_BACKTRACE", "1")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("lut: error:") && err.contains("bad.lut"),
        "{err}"
    );
    assert!(
        !err.contains("Stack backtrace") && !err.contains("Backtrace"),
        "{err}"
    );
}

#[test]
fn verify_detects_a_table_that_does_not_match_the_physics() {
    // Tamper with one stored outcome (and re-checksum it, so the file itself is valid): the
    // re-simulation of the stored setting must expose it.
    let grid = Grid::load(workspace().join("data/ci-grid.toml")).unwrap();
    let (d, _) = table::build_table(&grid, Some(2), true).unwrap();
    let mut data = d.into_data();
    for c in data.cells.iter_mut() {
        c.a_mean_g *= 0.8;
    }
    let tampered = Diagram::new(data).unwrap();
    let rows = verify::verify(&tampered, 4, 9).unwrap();
    assert!(rows.iter().all(|r| !r.ok), "{rows:?}");
}

#[test]
fn shard_ranges_cover_the_grid_exactly_once() {
    for count in [1usize, 7, 24, 4536] {
        for n in 1..=9 {
            let mut next = 0;
            for k in 1..=n {
                let r = table::shard_range(count, k, n).unwrap();
                assert_eq!(r.start, next);
                next = r.end;
            }
            assert_eq!(next, count);
        }
    }
    assert!(table::shard_range(10, 0, 3).is_err());
    assert!(table::shard_range(10, 4, 3).is_err());
}

#[test]
fn plot_makes_its_folder_and_a_bad_path_is_one_readable_line() {
    // `lut plot` into a missing folder printed the backend's debug text
    // (`ImageError(IoError(Os { code: 2, … }))`).
    let exe = env!("CARGO_BIN_EXE_lut");
    let table = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/default.lut");
    let dir = std::env::temp_dir().join(format!("lut-plot-{}", std::process::id()));
    let out = dir.join("not/yet/there.png");
    let run = |path: &std::path::Path| {
        std::process::Command::new(exe)
            .arg("plot")
            .arg(&table)
            .arg("--out")
            .arg(path)
            .output()
            .expect("lut runs")
    };
    let ok = run(&out);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    assert!(out.exists());
    let _ = std::fs::remove_dir_all(&dir);
    let bad = run(std::path::Path::new("/proc/no-such/x.png"));
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("/proc/no-such") && !err.contains("Os {"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

#[test]
fn the_repositorys_files_are_found_from_any_folder_of_it() {
    // `data/default.lut` and the studies' `data/…` defaults were relative to the current
    // folder: from `docs/` every one of them was "No such file". Run from two sub-folders
    // and from outside the repository (found beside the executable; a path found nowhere is
    // kept as typed and the error names it).
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = std::env::temp_dir().join(format!("lut-plot-cwd-{}", std::process::id()));
    let png = dir.join("surface.png");
    let lut_in = |cwd: &std::path::Path, args: &[&std::ffi::OsStr]| {
        let out = Command::new(env!("CARGO_BIN_EXE_lut"))
            .args(args)
            .current_dir(cwd)
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let table = std::ffi::OsStr::new("data/default.lut");
    let outside = std::env::temp_dir();
    for cwd in [repo.join("docs"), repo.join("lut/src"), outside.clone()] {
        let (code, err) = lut_in(&cwd, &["inspect".as_ref(), table]);
        assert_eq!(code, Some(0), "{}: {err}", cwd.display());
        let (code, err) = lut_in(
            &cwd,
            &["plot".as_ref(), table, "--out".as_ref(), png.as_ref()],
        );
        assert_eq!(code, Some(0), "{}: {err}", cwd.display());
        assert!(png.exists());
    }
    let (code, err) = lut_in(&outside, &["inspect".as_ref(), "nowhere/x.lut".as_ref()]);
    assert_eq!(code, Some(2));
    assert!(err.starts_with("lut: error: nowhere/x.lut"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
