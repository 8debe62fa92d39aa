//! The docs check catches what a review found by hand: a README command whose flag does
//! not exist (`lut plot --field a_max` after the field became `a_max_g`), numbers a command no
//! longer prints, a command that fails, a command block nobody checks, and a command in the
//! prose with a flag its tool does not take.

use std::path::Path;
use std::time::Duration;

use e2e_tests::docs::Checker;

const GOOD: &str = "\
<!-- docs: run -->
```sh
target/release/lut --help   # fine
```

<!-- docs: output -->
```sh
printf 'a\\nb\\n'
```

```text
a
b
```

<!-- docs: not run: needs a bench -->
```sh
./vcan-setup.sh --run -- target/release/lut plot data/default.lut --field a_max_g --plot x.png
candump -L vcan0 | sh -c cat
```

<!-- docs: synopsis -->
```sh
sensor-feeds --scenario F [--can IF | --no-can]
             [--check]
```

In prose: `lut plot FILE [--field F] --plot P.png\\|.svg`, `ecu --no-can`, `ecu`, `x --y`.
";

const BAD: &str = "\
<!-- docs: run -->
```sh
sh -c 'exit 3'
```

<!-- docs: output -->
```sh
printf 'a\\nc\\n'
```

```text
a
b
```

<!-- docs: not run: needs a bench -->
```sh
target/release/lut plot data/default.lut --fields a_max_g --plot x.png
no-such-program-x9 --x
```

```sh
ls
```

<!-- docs: synopsis -->
```sh
sensor-feeds --scenario F [--can-interface IF | --no-can]
```

In prose: `target/release/lut plot data/default.lut --fieldz a_max_g` and `ecu --no-can`.
";

fn check(text: &str) -> Vec<String> {
    let repo = e2e_tests::repo_root();
    let dir = repo.join("target/docs-check-test");
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join(format!("t{}.md", text.len()));
    std::fs::write(&file, text).expect("write");
    let rel = file.strip_prefix(&repo).expect("inside").to_path_buf();
    let mut c = Checker::new(&repo, Duration::from_secs(60));
    let (problems, _) = c.check_file(Path::new(&rel), &mut |_| {});
    problems
        .into_iter()
        .map(|p| format!("{}: {}", p.at, p.what))
        .collect()
}

#[test]
fn good_blocks_pass() {
    let p = check(GOOD);
    assert!(p.is_empty(), "{p:#?}");
}

#[test]
fn every_kind_of_drift_is_caught_at_its_line() {
    let p = check(BAD);
    let want = [
        (":2:", "`sh -c 'exit 3'` exited 3"),
        (":7:", "is not what `printf"),
        (":17:", "no flag --fields"),
        (":17:", "no-such-program-x9: not installed"),
        (":22:", "without a docs marker"),
        (":27:", "no flag --can-interface"),
        (":31:", "no flag --fieldz"),
    ];
    assert_eq!(p.len(), want.len(), "{p:#?}");
    for (at, what) in want {
        assert!(
            p.iter().any(|l| l.contains(at) && l.contains(what)),
            "{at} {what} not in {p:#?}"
        );
    }
}
