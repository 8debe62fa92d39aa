//! `sensor-feeds --replay` reads back what a recording holds: every publication of the feeds'
//! log (`feeds.postcard`, what they sent, at the time they sent it) and every CAN frame of
//! candump's log that the ECU did not send, in time order — from `run.mcap` alone, the file
//! `record` wrote from that folder (here by `offline-bench --record`, on the simulated clock).

use record::read::{feeds as read, Item};
use signals::{FeedItem, FeedLogRecord};

#[test]
fn a_recording_replays_every_feed_publication_and_every_can_input_in_order() {
    let name = "fault-satellite-dead-in-crash";
    let dir = std::env::temp_dir().join(format!("replay-read-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_offline-bench"))
        .arg("--scenario")
        .arg(e2e_tests::repo_root().join(format!("scenarios/{name}.toml")))
        .args(["--no-expect", "--record"])
        .arg(&dir)
        .output()
        .expect("offline-bench runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let run = dir.join(name);
    let rec = read(&std::fs::read(run.join("run.mcap")).expect("run.mcap")).expect("replayable");
    assert_eq!(rec.scenario, name);

    // The feeds' own log, record by record.
    let bytes = std::fs::read(run.join(record::FEEDS_LOG)).expect("feeds log");
    let mut rest = bytes.as_slice();
    let mut logged: Vec<FeedLogRecord> = Vec::new();
    while !rest.is_empty() {
        let (r, tail) = postcard::take_from_bytes(rest).expect("a record");
        logged.push(r);
        rest = tail;
    }
    let replayed: Vec<(u64, FeedItem)> = rec
        .items
        .iter()
        .filter_map(|(t, i)| match i {
            Item::Feed(f) => Some((*t, *f)),
            Item::Can(_) => None,
        })
        .collect();
    assert!(logged.len() > 1000, "{} records", logged.len());
    assert_eq!(replayed.len(), logged.len());
    // Publications of one instant may come in another order across topics: compare as sets of
    // one instant, and the instants in order.
    let key = |t: u64, i: &FeedItem| format!("{t} {i:?}");
    let mut a: Vec<String> = logged
        .iter()
        .map(|r| key(r.published_ns, &r.item))
        .collect();
    let mut b: Vec<String> = replayed.iter().map(|(t, i)| key(*t, i)).collect();
    assert!(
        replayed.windows(2).all(|w| w[0].0 <= w[1].0),
        "not in time order"
    );
    a.sort();
    b.sort();
    assert!(a == b, "the replay's feed items differ from the feeds' log");

    // The CAN inputs: candump's frames of every transmitter but the ECU, in order.
    let log = bus::candump::CandumpLog::read(&run.join("candump.log")).expect("candump.log");
    let inputs: Vec<bus::RawFrame> = log
        .frames
        .iter()
        .map(|f| f.frame)
        .filter(|f| bus::message_info(f.id).is_none_or(|m| m.transmitter != bus::ECU_NODE))
        .collect();
    let frames: Vec<bus::RawFrame> = rec
        .items
        .iter()
        .filter_map(|(_, i)| match i {
            Item::Can(f) => Some(*f),
            _ => None,
        })
        .collect();
    assert!(!inputs.is_empty());
    assert_eq!(frames, inputs);
    // The shift moves the time stamps inside the messages by the same offset.
    let first_object = rec
        .items
        .iter()
        .find_map(|(_, i)| match i {
            Item::Feed(FeedItem::Object(o)) => Some(*o),
            _ => None,
        })
        .expect("an object sample");
    match Item::Feed(FeedItem::Object(first_object)).shifted(-1_000) {
        Item::Feed(FeedItem::Object(o)) => {
            assert_eq!(o.timestamp_ns + 1_000, first_object.timestamp_ns)
        }
        other => panic!("{other:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_that_is_no_bench_recording_is_refused_with_a_reason() {
    let e = read(b"not an mcap").expect_err("refused");
    assert!(format!("{e:#}").contains("MCAP"), "{e:#}");
}
