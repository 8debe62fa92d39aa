//! One build for the demo and the suite (tests/Cargo.toml): a `--bins` build resolves the same
//! features in every crate the bench binaries share as the suite's `--bins --tests --examples`,
//! so neither command compiles those crates a second time after the other.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// Features per package (`name vX.Y.Z`) of the workspace's resolution with these edge kinds.
fn features(edges: &str) -> BTreeMap<String, BTreeSet<String>> {
    let o = Command::new(env!("CARGO"))
        .args([
            "tree",
            "--workspace",
            "--features",
            "bus/socket",
            "--prefix",
            "none",
        ])
        .args(["-e", edges, "-f", "{p}|{f}"])
        .current_dir(e2e_tests::repo_root())
        .output()
        .expect("cargo tree");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut map: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in String::from_utf8_lossy(&o.stdout).lines() {
        let Some((pkg, f)) = line.split_once('|') else {
            continue;
        };
        // "name v1.2.3 (path) (*)" → "name v1.2.3"
        let key: String = pkg.split_whitespace().take(2).collect::<Vec<_>>().join(" ");
        let f = f.trim_end_matches(" (*)");
        map.entry(key)
            .or_default()
            .extend(f.split(',').filter(|s| !s.is_empty()).map(str::to_owned));
    }
    map
}

#[test]
fn the_bench_binaries_and_the_tests_resolve_the_same_features_in_shared_crates() {
    let bins = features("normal,build");
    let all = features("normal,build,dev");
    assert!(bins.len() > 100, "cargo tree printed too little: {bins:?}");
    let differ: Vec<String> = bins
        .iter()
        .filter_map(|(pkg, f)| {
            let g = all.get(pkg)?;
            // itertools: in the bins' graph only bindgen's build-time copy (host, resolved apart);
            // the copy with more features is criterion's, a dev-dependency nothing shared uses.
            (f != g && !pkg.starts_with("itertools ")).then(|| {
                format!(
                    "{pkg}: the tests add {:?}",
                    g.difference(f).collect::<Vec<_>>()
                )
            })
        })
        .collect();
    assert!(
        differ.is_empty(),
        "a dev-dependency switches features on in crates the bench binaries share, so demo.sh \
         and test.sh compile them twice; ask for them in tests/Cargo.toml:\n{}",
        differ.join("\n")
    );
}
