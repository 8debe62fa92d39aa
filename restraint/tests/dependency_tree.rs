//! The core stays `no_std`: its normal dependency tree (what a microcontroller build would
//! compile) holds no std-only crate and no dependency built with its `std` or `alloc`
//! feature. The crate itself is `#![no_std]` without `extern crate alloc`, which the compiler
//! checks; this test checks what the compiler cannot see from here — the dependencies — by
//! asking cargo for the feature-resolved tree of this package alone.

use std::process::Command;

/// Crates that need an operating system or an allocator (the shell's crates). The
/// specification's list, plus the other std-only crates of this workspace.
const STD_ONLY: &[&str] = &[
    "iceoryx2",
    "socketcan",
    "nix",
    "anyhow",
    "toml",
    "serde_json",
    "hdrhistogram",
    "clap",
    "libc",
    "postcard",
    "triple_buffer",
    "tracing-subscriber",
    "rayon",
    "indicatif",
    "plotters",
    "regex",
    "argmin",
    "proptest",
    "criterion",
];

/// `name version [features]` of every package in the core's normal dependency tree.
fn tree() -> Vec<(String, Vec<String>, bool)> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "tree",
            "-p",
            env!("CARGO_PKG_NAME"),
            "-e",
            "normal",
            "--prefix",
            "none",
            "-f",
            "{p} [{f}]",
        ])
        .output()
        .expect("run cargo tree");
    assert!(
        out.status.success(),
        "cargo tree failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let name = l.split_whitespace().next().unwrap_or_default().to_owned();
            let feats = l
                .rsplit_once('[')
                .and_then(|(_, f)| f.split_once(']'))
                .map(|(f, _)| f.split(',').filter(|s| !s.is_empty()).map(str::to_owned))
                .map(Iterator::collect)
                .unwrap_or_default();
            (name, feats, l.contains("(proc-macro)"))
        })
        .collect()
}

#[test]
fn the_core_depends_on_no_std_only_crate() {
    let tree = tree();
    assert!(
        tree.iter().any(|(n, _, _)| n == "heapless"),
        "tree parse failed or heapless gone: {tree:?}"
    );
    let bad: Vec<_> = tree
        .iter()
        .filter(|(n, _, _)| STD_ONLY.contains(&n.as_str()))
        .map(|(n, _, _)| n.as_str())
        .collect();
    assert!(
        bad.is_empty(),
        "std-only crates in the core's tree: {bad:?}"
    );
}

#[test]
fn no_dependency_of_the_core_is_built_with_std_or_alloc() {
    let with_std: Vec<_> = tree()
        .into_iter()
        // Procedural macros run in the compiler on the build host, never on the target.
        .filter(|(_, f, proc_macro)| !proc_macro && f.iter().any(|f| f == "std" || f == "alloc"))
        .map(|(n, f, _)| format!("{n} {f:?}"))
        .collect();
    assert!(with_std.is_empty(), "built with std/alloc: {with_std:?}");
}
