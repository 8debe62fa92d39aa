//! Real bus test: our frames on vcan → `candump -L` → python-cantools with `restraint.dbc`
//! decodes the same physical values (and an independent CRC check); frames that cantools encodes
//! and `cansend` writes are decoded by our receive path.
//!
//! On a host without SocketCAN the visible test re-runs the `#[ignore]`d worker inside the
//! QEMU guest of `vcan-setup.sh --run`; with no route it FAILS (never skipped). The worker does
//! the bus side (our sockets, candump, cansend); cantools runs on this side, before and after it,
//! on files in the exchange folder both sides see: under emulation one Python start with
//! cantools costs ≈ 13 s, and this test once spent 27 of its 39 s on two of them.

#[path = "support/vcan_rerun.rs"]
mod vcan_rerun;

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime};

use bus::socket::BusSocket;
use bus::{encode_values, message_info, signal_values, signals_of, E2eChecker, RawFrame, MESSAGES};
use vcan_rerun::{iface, repo_root, run_here_or_in_guest};

/// Frames of each message we send for candump (k = 0..23: counters wrap once).
const OURS_PER_MESSAGE: u64 = 24;
/// Frames of each input message cantools encodes for cansend.
const CANTOOLS_PER_MESSAGE: u64 = 16;
/// What cantools encoded (`ID#HEX` lines, written before the worker runs).
const CANSEND_LINES: &str = "cansend.txt";
/// What candump logged of our frames (read by cantools after the worker).
const CANDUMP_LOG: &str = "candump.log";

#[test]
fn real_bus_candump_cantools_cansend() {
    let dir = exchange_dir();
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (requests, _) = cantools_requests();
    let lines = cantools(
        "encode",
        &serde_json::to_vec(&requests).unwrap(),
        "requests.json",
    );
    std::fs::write(dir.join(CANSEND_LINES), &lines).unwrap();

    run_here_or_in_guest("inner_real_bus_worker", real_bus_worker_body);

    let log = std::fs::read(dir.join(CANDUMP_LOG)).expect("the worker's candump log");
    check_cantools_decoded(&cantools("decode", &log, CANDUMP_LOG));
}

#[test]
#[ignore = "worker: needs a vcan interface; run by real_bus_candump_cantools_cansend"]
fn inner_real_bus_worker() {
    real_bus_worker_body();
}

/// The folder both sides of the test see: under the target directory, which the guest of
/// `vcan-setup.sh` shares read-write at the same path.
fn exchange_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("real-bus")
}

/// Runs `bus/tests/cantools_check.py MODE DBC FILE` on `input` (written to `name` in the
/// exchange folder) and returns its stdout.
fn cantools(mode: &str, input: &[u8], name: &str) -> Vec<u8> {
    let path = exchange_dir().join(format!("cantools-{mode}-{name}"));
    std::fs::write(&path, input).unwrap();
    let out = Command::new(python3())
        .arg(repo_root().join("bus/tests/cantools_check.py"))
        .arg(mode)
        .arg(repo_root().join("bus/restraint.dbc"))
        .arg(&path)
        .output()
        .expect("run python3 cantools helper");
    assert!(
        out.status.success(),
        "cantools {mode} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// Deterministic pseudo-random raw values covering both range ends.
fn sample_raws(id: u32, k: u64) -> Vec<i64> {
    let sigs = signals_of(id).unwrap();
    let mut x = 0x9E37_79B9_7F4A_7C15u64 ^ (u64::from(id) << 32) ^ k;
    sigs.iter()
        .map(|s| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            match k {
                0 => s.raw_min,
                1 => s.raw_max,
                _ => s.raw_min + (x % ((s.raw_max - s.raw_min + 1) as u64)) as i64,
            }
        })
        .collect()
}

/// Physical values for a frame with E2E fields valid (counter = k mod 16, CRC by our protector
/// logic; the python side checks the CRC independently).
fn build(id: u32, k: u64) -> (RawFrame, Vec<f64>) {
    let sigs = signals_of(id).unwrap();
    let mut phys: Vec<f64> = sample_raws(id, k)
        .iter()
        .zip(sigs)
        .map(|(r, s)| *r as f64 * s.factor + s.offset)
        .collect();
    let info = message_info(id).unwrap();
    if let Some(did) = info.e2e_data_id {
        let ci = sigs.iter().position(|s| s.name == "Crc").unwrap();
        let ai = sigs.iter().position(|s| s.name == "AliveCounter").unwrap();
        phys[ai] = (k % 16) as f64;
        let f = encode_values(id, &phys).unwrap();
        phys[ci] = f64::from(bus::e2e_crc(
            did,
            (sigs[ci].start_bit / 8) as usize,
            f.payload(),
        ));
    }
    (encode_values(id, &phys).unwrap(), phys)
}

fn close(a: f64, b: f64, factor: f64) -> bool {
    (a - b).abs() <= factor * 1e-3 + b.abs() * 1e-6
}

fn need(cmd: &str) {
    let ok = Command::new("sh")
        .args(["-c", &format!("command -v {cmd}")])
        .stdout(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    assert!(ok, "{cmd} is missing (./vcan-setup.sh installs can-utils)");
}

fn real_bus_worker_body() {
    need("candump");
    need("cansend");
    let iface = iface();
    let dir = exchange_dir();
    let lines: Vec<String> = std::fs::read_to_string(dir.join(CANSEND_LINES))
        .expect("the frames cantools encoded (written by the visible test before the worker)")
        .lines()
        .map(str::to_owned)
        .collect();

    // ---------- our frames → candump -L (→ cantools, after the worker)
    let log = dir.join(CANDUMP_LOG);
    let mut candump = Command::new("candump")
        .args(["-L", &iface])
        .stdout(std::fs::File::create(&log).unwrap())
        .spawn()
        .expect("spawn candump");
    let mut tx = BusSocket::open(&iface, &[]).expect("open tx socket");
    // our rx socket with a kernel filter for the ECU's inputs only
    let input_ids: Vec<u32> = MESSAGES
        .iter()
        .filter(|m| m.transmitter != bus::ECU_NODE)
        .map(|m| m.id)
        .collect();
    let mut rx = BusSocket::open(&iface, &input_ids).expect("open rx socket");
    // Wait until candump is listening: send a probe frame (unknown id) until it shows up.
    let t0 = Instant::now();
    loop {
        tx.send(&RawFrame::new(0x7FF, &[0xAA])).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        if std::fs::read_to_string(&log)
            .unwrap_or_default()
            .contains("7FF#AA")
        {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "candump never saw the probe frame"
        );
    }
    for (f, _) in our_frames() {
        tx.send(&f).unwrap();
    }
    std::thread::sleep(Duration::from_millis(500));
    candump.kill().ok();
    candump.wait().ok();
    // error frame: counted by our socket, never decoded
    let errs_before = rx.stats().error_frames;
    let status = Command::new("cansend")
        .args([&iface, "20000004#0000000000000000"])
        .status()
        .unwrap();
    assert!(status.success());

    // Kernel filter: only input ids reached rx (plus the error frame, counted not returned).
    let mut checker = E2eChecker::new();
    let mut got_inputs = 0;
    let deadline = Instant::now() + Duration::from_secs(5);
    while Instant::now() < deadline {
        match rx.recv().unwrap() {
            Some(f) => {
                assert!(
                    input_ids.contains(&f.frame.id),
                    "filter let {:#x} through",
                    f.frame.id
                );
                let ts = f.kernel_time.expect("kernel receive timestamp");
                let age = SystemTime::now().duration_since(ts).unwrap_or_default();
                assert!(age < Duration::from_secs(60), "timestamp {age:?} old");
                checker
                    .check_frame(&f.frame)
                    .expect("our own frames pass our checker");
                got_inputs += 1;
            }
            None if got_inputs == OURS_PER_MESSAGE as usize * input_ids.len()
                && rx.stats().error_frames > errs_before =>
            {
                break
            }
            None => std::thread::sleep(Duration::from_millis(10)),
        }
    }
    assert_eq!(got_inputs, OURS_PER_MESSAGE as usize * input_ids.len());
    assert_eq!(
        rx.stats().error_frames,
        errs_before + 1,
        "error frame not counted"
    );

    // ---------- cantools encoded (before the worker) → cansend → our decoder
    let (_, want) = cantools_requests();
    assert_eq!(lines.len(), want.len());
    for (line, (id, phys)) in lines.iter().zip(&want) {
        let st = Command::new("cansend")
            .args([&iface, line])
            .status()
            .unwrap();
        assert!(st.success(), "cansend {line}");
        let t = Instant::now();
        let f = loop {
            if let Some(f) = rx.recv().unwrap() {
                break f;
            }
            assert!(
                t.elapsed() < Duration::from_secs(5),
                "frame {line} never arrived"
            );
            std::thread::sleep(Duration::from_millis(2));
        };
        assert_eq!(f.frame.id, *id);
        let msg = checker
            .check_frame(&f.frame)
            .unwrap_or_else(|e| panic!("our decoder rejected cansend {line}: {e}"));
        let mut vals = [0f64; 16];
        let n = signal_values(&msg, &mut vals).unwrap();
        for (s, (got, w)) in signals_of(*id)
            .unwrap()
            .iter()
            .zip(vals[..n].iter().zip(phys))
        {
            if s.name == "Crc" {
                continue; // python computed it; the checker accepted it
            }
            assert!(
                close(*got, *w, s.factor),
                "{line}: {} = {got}, cantools encoded {w}",
                s.name
            );
        }
    }
    eprintln!(
        "our decoder accepted {} frames encoded by cantools and sent with cansend; rx stats {:?}",
        lines.len(),
        checker.stats()
    );
}

/// The cantools venv's Python (`tests/setup-host.sh` makes `target/pyenv`), so that `cargo
/// test` finds cantools without the venv on PATH; plain `python3` where there is none.
fn python3() -> std::path::PathBuf {
    let venv = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/pyenv/bin/python3");
    if venv.exists() {
        venv
    } else {
        "python3".into()
    }
}

/// Our frames for candump, with their physical values: every message, k = 0..23.
fn our_frames() -> Vec<(RawFrame, (u32, Vec<f64>))> {
    let mut v = Vec::new();
    for k in 0..OURS_PER_MESSAGE {
        for m in MESSAGES {
            let (f, phys) = build(m.id, k);
            v.push((f, (m.id, phys)));
        }
    }
    v
}

/// What cantools is asked to encode (one JSON request per frame) and the physical values each
/// frame must decode to on our side. The counters continue the sequence our checker has
/// already seen from our frames (k = 0..23).
fn cantools_requests() -> (Vec<serde_json::Value>, Vec<(u32, Vec<f64>)>) {
    let mut reqs = Vec::new();
    let mut want = Vec::new();
    for k in 0..CANTOOLS_PER_MESSAGE {
        for m in MESSAGES.iter().filter(|m| m.transmitter != bus::ECU_NODE) {
            let (_, phys) = build(m.id, k + 100);
            let sigs = signals_of(m.id).unwrap();
            let mut obj = serde_json::Map::new();
            for (s, v) in sigs.iter().zip(&phys) {
                obj.insert(s.name.to_string(), serde_json::json!(v));
            }
            let counter = (OURS_PER_MESSAGE + k) % 16;
            obj.insert("AliveCounter".into(), serde_json::json!(counter));
            let mut phys = phys;
            let ai = sigs.iter().position(|s| s.name == "AliveCounter").unwrap();
            phys[ai] = counter as f64;
            reqs.push(serde_json::json!({"name": m.name, "signals": obj}));
            want.push((m.id, phys));
        }
    }
    (reqs, want)
}

/// cantools' decode of candump's log of our frames (`stdout`: its JSON) against what we sent.
fn check_cantools_decoded(stdout: &[u8]) {
    let expected: Vec<(u32, Vec<f64>)> = our_frames().into_iter().map(|(_, e)| e).collect();
    let decoded: serde_json::Value = serde_json::from_slice(stdout).unwrap();
    let decoded: Vec<_> = decoded
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| d["id"].as_u64() != Some(0x7FF))
        .collect();
    assert_eq!(
        decoded.len(),
        expected.len(),
        "candump captured a different number of frames"
    );
    for (d, (id, phys)) in decoded.iter().zip(&expected) {
        assert_eq!(d["id"].as_u64().unwrap(), u64::from(*id));
        let info = message_info(*id).unwrap();
        assert_eq!(d["name"].as_str().unwrap(), info.name);
        if info.e2e_data_id.is_some() {
            assert_eq!(
                d["crc_ok"].as_bool(),
                Some(true),
                "python's CRC check of {}",
                info.name
            );
        }
        for (s, want) in signals_of(*id).unwrap().iter().zip(phys) {
            let got = d["signals"][s.name].as_f64().unwrap();
            assert!(
                close(got, *want, s.factor),
                "{}.{}: cantools {got}, we sent {want}",
                info.name,
                s.name
            );
        }
    }
    eprintln!(
        "cantools decoded {} frames written by us to the same values",
        decoded.len()
    );
}
