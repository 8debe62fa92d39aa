#!/usr/bin/env python3
"""Checks a run's run.mcap against the run folder with readers independent of the project's
code: Foxglove's `mcap` package reads the file, `cantools` decodes the frames with the DBC.

    check_mcap.py RUN_DIR DBC [--mcap FILE] [--full]

--full: the folder is a whole bench run: commands.jsonl and report.json must be there and the
file's log times must be UTC (the bench's CLOCK_MONOTONIC + a realtime − monotonic offset
measured from the run, as the metadata says).

Checked:
  * every frame of candump.log is on /can/raw, in order, with the same id and bytes and a
    publish time equal to candump's stamp (±1 µs); every error frame on /can/error, with its
    classes and detail bytes;
  * with log times in UTC, every frame's log time is its publish time (candump's stamp) and
    every other message's log time is its bench time plus the file's realtime − monotonic
    offset (metadata `bench`); the checks below compare bench times (log time − offset), and
    a frame's bench time is its publish time minus that offset, the same for every frame;
  * every frame of a DBC message is on /can/<name> with the same times, and each signal's value
    equals cantools' decode of the same bytes (scaled, no value-table names), and each
    value-table signal's schema names its values as cantools' choices do, and each schema
    carries the signal's DBC comment;
  * with commands.jsonl: every record is on /stubs/commands unchanged, at its rx_mono_ns;
  * with report.json: one /stubs/actions message per action, one /stubs/verdict carrying the
    report's required fire time (true_crash.required_ms) and margin_ms; /truth/world
    (required with --full) every ms from the report's start, its contact (distance 0) within
    1 ms of the report's contact time;
  * with diagnostics.postcard: /ecu/diagnostics holds as many records as the metadata says,
    each at its own timestamp_ns, with the schema's fields, cycle counts rising, the gaps as
    counted in the metadata; /ecu/predicted_pulse at diagnostics times, each pulse as long as
    its pulse_points;
  * /ecu/log (foxglove.Log): one message at each /ecu/diagnostics record whose mode or degraded
    reasons differ from the one before (the first too), naming the new mode;
  * every topic's schema offers its messages' fields: each key of each JSON message, nested
    objects included, is a property of the channel's JSON Schema (what Foxglove's panels list).
Prints one line per check and exits 1 on the first failure.
"""

import argparse
import json
import math
import pathlib
import re
import sys

import cantools
from mcap.reader import make_reader

LINE = re.compile(r"^\((\d+)\.(\d{6})\)\s+(\S+)\s+([0-9A-Fa-f]+)#([0-9A-Fa-f]*)\s*$")


def fail(msg):
    print(f"check_mcap: FAIL: {msg}")
    sys.exit(1)


CAN_ERR_FLAG = 0x20000000  # linux/can.h: an eight-digit id with this bit is an error frame


def candump_frames(path):
    frames = []
    for line in path.read_text().splitlines():
        m = LINE.match(line)
        if not m:
            continue  # remote / FD frames: not data frames of this bus
        sec, usec, iface, ident, data = m.groups()
        if len(ident) == 8 and int(ident, 16) & CAN_ERR_FLAG:
            continue  # an error frame (candump_error_frames)
        frames.append(
            {
                "t_ns": (int(sec) * 1_000_000 + int(usec)) * 1000,
                "iface": iface,
                "id": int(ident, 16),
                "extended": len(ident) == 8,
                "data": bytes.fromhex(data),
            }
        )
    return frames


def candump_error_frames(path):
    """candump's error frames: time, interface, the error classes (id without CAN_ERR_FLAG) and
    the eight detail bytes (linux/can/error.h)."""
    errors = []
    for line in path.read_text().splitlines():
        m = LINE.match(line)
        if not m:
            continue
        sec, usec, iface, ident, data = m.groups()
        if len(ident) != 8 or not int(ident, 16) & CAN_ERR_FLAG:
            continue
        errors.append(
            {
                "t_ns": (int(sec) * 1_000_000 + int(usec)) * 1000,
                "iface": iface,
                "class": int(ident, 16) & ~CAN_ERR_FLAG,
                "data": bytes.fromhex(data).ljust(8, b"\0"),
            }
        )
    return errors


def frames_by_message(db, frames):
    """The frames of each DBC message (id, IDE and length as the DBC says), in bus order: a list
    of (cantools message, frames)."""
    by_id = {}
    for fr in frames:
        try:
            m = db.get_message_by_frame_id(fr["id"])
        except KeyError:
            continue
        if fr["extended"] != m.is_extended_frame or len(fr["data"]) != m.length:
            continue
        by_id.setdefault(m.frame_id, (m, []))[1].append(fr)
    return list(by_id.values())


def check_sensors(topics, bench, full):
    """/sensors/*: what the feeds published, as they logged it (their own clock stamps): each
    topic's sequences rising, a batch's samples before its publish and after the previous
    batch's, and every accelerometer batch a diagnostics record names as read is on the topic."""
    n = int(bench.get("feeds_records") or 0)
    satellites = ("/sensors/satellite_left", "/sensors/satellite_right")
    got = sum(len(topics.get(t, [])) for t in ("/sensors/object", "/sensors/crash_accel", "/sensors/safing_accel")
              + satellites)
    if got != n:
        fail(f"/sensors/*: {got} messages, metadata says {n} feed records")
    if full and not topics.get("/sensors/crash_accel"):
        fail("--full: no /sensors/crash_accel")
    for topic in ("/sensors/crash_accel", "/sensors/safing_accel"):
        last_seq, last_sample = 0, -1
        for log_t, pub_t, m, _ in topics.get(topic, []):
            if m["sequence"] <= last_seq:
                fail(f"{topic}: sequence {m['sequence']} after {last_seq}")
            if m["count"] != len(m["accel_mps2"]) or \
                    m["newest_sample_ns"] != m["first_timestamp_ns"] + (m["count"] - 1) * m["sample_period_ns"]:
                fail(f"{topic}: batch {m['sequence']}: count / newest sample inconsistent")
            if m["first_timestamp_ns"] <= last_sample or m["newest_sample_ns"] > log_t or pub_t != log_t:
                fail(f"{topic}: batch {m['sequence']}: samples {m['first_timestamp_ns']}…{m['newest_sample_ns']} "
                     f"not after the previous ({last_sample}) and before the publish ({log_t})")
            last_seq, last_sample = m["sequence"], m["newest_sample_ns"]
    frames = 0
    for topic in satellites:
        last_seq, last_sample = 0, -1
        for log_t, pub_t, m, _ in topics.get(topic, []):
            if m["sequence"] <= last_seq or m["count"] != len(m["frames"]) or \
                    m["newest_sample_ns"] != m["first_timestamp_ns"] + (m["count"] - 1) * m["sample_period_ns"]:
                fail(f"{topic}: batch {m['sequence']} after {last_seq}: count / newest sample inconsistent")
            # A frame travels one sync slot after its sample.
            if m["first_timestamp_ns"] <= last_sample or \
                    m["newest_sample_ns"] + m["sample_period_ns"] > log_t or pub_t != log_t:
                fail(f"{topic}: batch {m['sequence']}: frames not after the previous or not a slot before the publish")
            for word, code in zip(m["frames"], m["decel_codes"]):
                # PSI5 10-bit data with even parity in bit 10, decoded here on its own.
                data = word & 0x3FF
                parity_ok = word < 0x800 and bin(word).count("1") % 2 == 0
                value = data - 0x400 if data & 0x200 else data
                expect = value if parity_ok and abs(value) <= 480 else None
                if code != expect:
                    fail(f"{topic}: batch {m['sequence']}: frame {word:#05x} decodes to {expect}, recorded {code}")
            frames += len(m["frames"])
            last_seq, last_sample = m["sequence"], m["newest_sample_ns"]
    last_seq = 0
    for log_t, _, m, _ in topics.get("/sensors/object", []):
        if m["sequence"] <= last_seq or m["timestamp_ns"] > log_t:
            fail(f"/sensors/object: {m['sequence']} after {last_seq}, measured {m['timestamp_ns']} published {log_t}")
        last_seq = m["sequence"]
    crash = {m["sequence"] for _, _, m, _ in topics.get("/sensors/crash_accel", [])}
    if crash:
        named = {m["last_accel_sequence"] for _, _, m, _ in topics.get("/ecu/diagnostics", [])} - {0}
        if not named <= crash:
            fail(f"/ecu/diagnostics: batches read but never published: {sorted(named - crash)[:5]}")
    print(f"check_mcap: /sensors: {n} publications of the feeds in order, samples before their publish; "
          f"every crash batch the ECU read is among them; {frames} satellite frames, parity and codes decoded alike")


def fields_not_in_schema(msg, schema, path=""):
    """The dotted paths of msg's object keys that the JSON Schema does not name."""
    if not isinstance(msg, dict):
        return []
    props = schema.get("properties", {})
    missing = []
    for k, v in msg.items():
        if k not in props:
            missing.append(path + k)
        else:
            missing += fields_not_in_schema(v, props[k], path + k + ".")
    return missing


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run_dir", type=pathlib.Path)
    ap.add_argument("dbc", type=pathlib.Path)
    ap.add_argument("--mcap", type=pathlib.Path)
    ap.add_argument("--full", action="store_true")
    ap.add_argument("--layout", type=pathlib.Path, help="a Foxglove layout whose every path must resolve in the file")
    a = ap.parse_args()
    mcap_path = a.mcap or a.run_dir / "run.mcap"
    db = cantools.database.load_file(str(a.dbc))

    topics = {}
    with open(mcap_path, "rb") as f:
        reader = make_reader(f)
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        summary = reader.get_summary()
        channels = {c.topic for c in summary.channels.values()} if summary else set()
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            topics.setdefault(channel.topic, []).append(
                (message.log_time, message.publish_time, json.loads(message.data), schema)
            )
    bench = meta.get("bench")
    if bench is None:
        fail("no `bench` metadata")
    # The ECU's configuration, when the run folder has it, rides along verbatim.
    config = a.run_dir / "ecu-config.toml"
    if config.exists() and meta.get("ecu_config", {}).get("toml") != config.read_text():
        fail("metadata `ecu_config` is not the run folder's ecu-config.toml")
    offset = int(bench["realtime_minus_monotonic_ns"]) if bench.get("realtime_minus_monotonic_ns") else 0
    utc = "UTC" in bench.get("log_time_clock", "")
    if a.full:
        for f in ("commands.jsonl", "report.json"):
            if not (a.run_dir / f).exists():
                fail(f"--full: no {f} in {a.run_dir}")
        if not bench.get("realtime_minus_monotonic_ns") or not utc:
            fail(f"--full: log times are not UTC with a measured offset ({bench.get('log_time_clock')})")
    if utc:
        # Every frame's log time is candump's own UTC stamp; then every message back on the
        # bench's clock for the checks below.
        for i, (log_t, pub_t, _, _) in enumerate(topics.get("/can/raw", [])):
            if log_t != pub_t:
                fail(f"frame {i}: UTC log time {log_t} is not candump's stamp {pub_t}")
        topics = {t: [(lt - offset, pt, m, sc) for lt, pt, m, sc in msgs] for t, msgs in topics.items()}
        print(f"check_mcap: log times in UTC: every frame at candump's stamp, every message at its bench time + {offset} ns")
    print(f"check_mcap: {mcap_path}: {sum(map(len, topics.values()))} messages, "
          f"route {bench.get('route')}, timing {bench.get('timing')}, offset {offset} ns")

    frames = candump_frames(a.run_dir / "candump.log")
    raw = topics.get("/can/raw", [])
    if len(raw) != len(frames):
        fail(f"/can/raw has {len(raw)} frames, candump.log {len(frames)}")
    for i, (fr, (log_t, pub_t, msg, _)) in enumerate(zip(frames, raw)):
        if msg["id"] != fr["id"] or bytes(msg["data"]) != fr["data"] or msg["dlc"] != len(fr["data"]):
            fail(f"frame {i}: {msg} is not candump's {fr['id']:x}#{fr['data'].hex()}")
        if abs(pub_t - fr["t_ns"]) > 1000:
            fail(f"frame {i}: publish time {pub_t} vs candump {fr['t_ns']} ns")
        if log_t != pub_t - offset:
            fail(f"frame {i}: log time {log_t} is not publish time − offset ({pub_t - offset})")
    print(f"check_mcap: /can/raw: all {len(frames)} frames of candump.log, bytes and times (±1 µs) equal")

    errors = candump_error_frames(a.run_dir / "candump.log")
    logged = topics.get("/can/error", [])
    if len(logged) != len(errors):
        fail(f"/can/error has {len(logged)} error frames, candump.log {len(errors)}")
    for i, (e, (_, pub_t, msg, _)) in enumerate(zip(errors, logged)):
        if msg["class"] != e["class"] or bytes(msg["data"]) != e["data"] or msg["interface"] != e["iface"]:
            fail(f"error frame {i}: {msg} is not candump's {e['class']:x}#{e['data'].hex()}")
        if abs(pub_t - e["t_ns"]) > 1000:
            fail(f"error frame {i}: publish time {pub_t} vs candump {e['t_ns']} ns")
    if errors:
        print(f"check_mcap: /can/error: all {len(errors)} error frames of candump.log, classes, bytes and times equal")

    decoded = 0
    by_id = {m.name: [(fr, m) for fr in frs] for m, frs in frames_by_message(db, frames)}
    for name, items in by_id.items():
        got = topics.get(f"/can/{name}", [])
        if len(got) != len(items):
            fail(f"/can/{name}: {len(got)} messages, candump.log has {len(items)} frames")
        for (fr, m), (log_t, pub_t, msg, _) in zip(items, got):
            if abs(pub_t - fr["t_ns"]) > 1000 or log_t != pub_t - offset:
                fail(f"/can/{name}: times {log_t}/{pub_t} vs candump {fr['t_ns']}")
            want = m.decode(fr["data"], decode_choices=False, scaling=True)
            if set(want) != set(msg):
                fail(f"/can/{name}: signals {sorted(msg)} vs cantools {sorted(want)}")
            for sig, v in want.items():
                if not math.isclose(float(msg[sig]), float(v), rel_tol=1e-9, abs_tol=1e-9):
                    fail(f"/can/{name}.{sig}: {msg[sig]} vs cantools {v} ({fr['data'].hex()})")
            decoded += 1
        # The schema names each value-table signal's values as cantools' choices do.
        if got:
            props = json.loads(got[0][3].data)["properties"]
            m = items[0][1]
            for sig in m.signals:
                if sig.comment and not props[sig.name].get("description", "").startswith(sig.comment):
                    fail(f"/can/{name}.{sig.name}: the schema's description does not carry the DBC comment")
                want = {int(k): str(v) for k, v in (sig.choices or {}).items()}
                have = {int(e["const"]): e["title"] for e in props[sig.name].get("oneOf", [])}
                if have != want:
                    fail(f"/can/{name}.{sig.name}: schema values {have} vs the DBC's {want}")
    print(f"check_mcap: /can/<message>: {decoded} frames of {len(by_id)} DBC messages, every signal equals cantools' decode, every value table and comment in the schema")

    cmd_path = a.run_dir / "commands.jsonl"
    if cmd_path.exists():
        want, unreadable = [], 0
        for l in cmd_path.read_text().splitlines():
            if not l.strip():
                continue
            try:
                v = json.loads(l)
            except ValueError:
                v = None
            if isinstance(v, dict):
                want.append(v)
            else:
                unreadable += 1
        if unreadable != int(bench.get("commands_lines_unreadable", 0)):
            fail(f"commands.jsonl: {unreadable} unreadable lines, metadata says {bench.get('commands_lines_unreadable')}")
        got = topics.get("/stubs/commands", [])
        if len(got) != len(want):
            fail(f"/stubs/commands: {len(got)} vs {len(want)} records")
        for w, (log_t, _, msg, _) in zip(want, got):
            if msg != w or log_t != w["rx_mono_ns"]:
                fail(f"/stubs/commands: {msg} at {log_t} vs {w}")
        print(f"check_mcap: /stubs/commands: all {len(want)} records unchanged at their rx_mono_ns")

    rep_path = a.run_dir / "report.json"
    if rep_path.exists():
        rep = json.loads(rep_path.read_text())
        acts = topics.get("/stubs/actions", [])
        if len(acts) != len(rep["actions"]):
            fail(f"/stubs/actions: {len(acts)} vs {len(rep['actions'])} actions")
        for w, (log_t, _, msg, _) in zip(rep["actions"], acts):
            if msg["what"] != w["what"] or abs(log_t - (rep["start_ns"] + w["t_ms"] * 1e6)) > 1:
                fail(f"/stubs/actions: {msg} at {log_t} vs {w}")
        verdicts = topics.get("/stubs/verdict", [])
        if len(verdicts) != 1:
            fail("/stubs/verdict: not exactly one message")
        # The required fire time ("127 mm - 30 ms" of the true pulse) and the airbag's margin
        # against it, as report.json has them.
        verdict = verdicts[0][2]
        want_required = (rep.get("true_crash") or {}).get("required_ms")
        got_required = (verdict.get("true_crash") or {}).get("required_ms")
        if got_required != want_required or verdict.get("margin_ms") != rep.get("margin_ms"):
            fail(f"/stubs/verdict: required {got_required} / margin {verdict.get('margin_ms')} "
                 f"vs report {want_required} / {rep.get('margin_ms')}")
        ms = lambda v: "none" if v is None else f"{v:+.1f} ms"
        print(f"check_mcap: /stubs/actions: {len(acts)} actions at start + t_ms; one verdict "
              f"(required fire {ms(want_required)}, margin {ms(rep.get('margin_ms'))})")
    truth = topics.get("/truth/world", [])
    if a.full and not truth:
        fail("--full: no /truth/world")
    if truth:
        # From the run's start (the stubs' report's, or a simulated run's, in the metadata).
        start = int(bench.get("start_ns") or -1)
        times = [t for t, _, _, _ in truth]
        if times[0] != start or any(b - a_ != 1_000_000 for a_, b in zip(times, times[1:])):
            fail(f"/truth/world: not every ms from the run's start ({start})")
        if rep_path.exists() and json.loads(rep_path.read_text()).get("contact_ns"):
            contact = json.loads(rep_path.read_text())["contact_ns"]
            first_contact = next((t for t, _, m, _ in truth if m["distance_m"] <= 0.0), None)
            if first_contact is None or abs(first_contact - contact) > 1_000_000:
                fail(f"/truth/world: contact at {first_contact}, the stubs' report says {contact}")
        print(f"check_mcap: /truth/world: {len(truth)} states every ms from the start"
              + ("; contact where the report has it" if rep_path.exists() else ""))
    if (a.run_dir / "diagnostics.postcard").exists():
        diag = topics.get("/ecu/diagnostics", [])
        n = int(bench.get("diagnostics_records", -1))
        if len(diag) != n or n <= 0:
            fail(f"/ecu/diagnostics: {len(diag)} records, metadata says {n}")
        fields = None
        last = -1
        gaps = 0
        for log_t, pub_t, msg, schema in diag:
            if fields is None:
                fields = set(json.loads(schema.data)["properties"])
            if set(msg) != fields:
                fail(f"/ecu/diagnostics: fields {sorted(set(msg) ^ fields)} differ from the schema")
            if log_t != msg["timestamp_ns"] or pub_t != log_t:
                fail(f"/ecu/diagnostics: log time {log_t} vs timestamp_ns {msg['timestamp_ns']}")
            if msg["cycle_count"] <= last:
                fail(f"/ecu/diagnostics: cycle_count {msg['cycle_count']} after {last}")
            if last >= 0:
                gaps += msg["cycle_count"] - last - 1
            last = msg["cycle_count"]
        if gaps != int(bench.get("diagnostics_missed", -1)):
            fail(f"/ecu/diagnostics: {gaps} cycles missing, metadata says {bench.get('diagnostics_missed')}")
        pulses = topics.get("/ecu/predicted_pulse", [])
        if not pulses or any(len(m["pulse_accel_mps2"]) != m["pulse_points"] for _, _, m, _ in pulses):
            fail("/ecu/predicted_pulse: missing, or a pulse whose length is not its pulse_points")
        stamps = {t for t, _, _, _ in diag}
        if any(t not in stamps for t, _, _, _ in pulses):
            fail("/ecu/predicted_pulse: a pulse at a time no diagnostics record has")
        changes, before = [], None
        for t, _, msg, _ in diag:
            now = (msg["mode_name"], tuple(msg["degraded"]))
            if now != before:
                changes.append((t, msg["mode_name"]))
            before = now
        logs = topics.get("/ecu/log", [])
        if len(logs) != len(changes) or any(s.name != "foxglove.Log" for _, _, _, s in logs):
            fail(f"/ecu/log: {len(logs)} foxglove.Log messages, the diagnostics change {len(changes)} times")
        for (t, mode), (lt, _, m, _) in zip(changes, logs):
            stamp = m["timestamp"]["sec"] * 1_000_000_000 + m["timestamp"]["nsec"]
            if lt != t or stamp != t or f"mode {mode}" not in m["message"] and f"-> {mode}" not in m["message"]:
                fail(f"/ecu/log: {m} at {lt} is not the change to {mode} at {t}")
        print(f"check_mcap: /ecu/log: {len(logs)} foxglove.Log messages, one per change of mode or degraded reasons")
        print(f"check_mcap: /ecu/diagnostics: {len(diag)} records at their timestamps, {gaps} cycles never published; {len(pulses)} predicted pulses")
        if a.full and not diag:
            fail("--full: no diagnostics")
    elif a.full:
        fail("--full: no diagnostics.postcard")
    check_sensors(topics, bench, a.full)
    offered = 0
    for topic, msgs in sorted(topics.items()):
        for _, _, msg, schema in msgs:
            missing = fields_not_in_schema(msg, json.loads(schema.data))
            if missing:
                fail(f"{topic}: fields {missing} are not in the schema {schema.name}")
        offered += 1
    print(f"check_mcap: every field of every message of {offered} topics is in its schema")
    if a.layout:
        layout = json.loads(a.layout.read_text())
        paths = []
        for cfg in layout["configById"].values():
            paths += [p["value"] for p in cfg.get("paths", [])]
            if "topicPath" in cfg:
                paths.append(cfg["topicPath"])
        for p in paths:
            topic, _, field = p.partition(".")
            field = field.split("[", 1)[0]  # accel_mps2[0]: the array's field
            if topic not in channels:
                fail(f"layout: topic {topic} is not in the file")
            if field and topic in topics and field not in topics[topic][0][2]:
                fail(f"layout: {topic} has no field {field}")
            if field and topic not in topics:
                fail(f"layout: {topic} has no message to show {field}")
        print(f"check_mcap: layout {a.layout.name}: all {len(paths)} paths resolve")
    print("check_mcap: OK")


if __name__ == "__main__":
    main()
