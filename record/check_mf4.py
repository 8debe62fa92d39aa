#!/usr/bin/env python3
"""Checks a run's run.mf4 against the run folder with readers independent of the project's
code: `asammdf` reads the file and decodes its bus logging with the DBC, `cantools` decodes the
same frames from candump.log, Foxglove's `mcap` reads the run's diagnostics from run.mcap.

    check_mf4.py DBC RUN_DIR [RUN_DIR …] [--mf4 FILE] [--mcap FILE]

(Several folders in one call: the readers are imported once.)

Checked:
  * an MDF 4.1 file; one channel group flagged as bus event with a CAN bus source and the
    ASAM bus-logging channels CAN_DataFrame.{BusChannel,ID,IDE,DLC,DataLength,DataBytes};
  * every frame of candump.log is in it, in order, with the same id, IDE, length and bytes and
    a time (header start + t) equal to candump's stamp (±1 µs);
  * asammdf's extract_bus_logging with the DBC yields every DBC message that is on the bus,
    each signal's samples and times equal to cantools' decode of the same frames;
  * every error frame of candump.log in the CAN_ErrorFrame group (no group without one), same
    classes, bytes and time, its ASAM ErrorType named;
  * the DBC is attached to CAN_DataFrame;
  * with run.mcap holding /ecu/diagnostics: the MF4's EcuDiagnostics group has one record per
    MCAP record, every numeric field a channel with the same value, and each record's time
    equal to the MCAP's log time + the realtime − monotonic offset (±1 µs).
Prints one line per check and exits 1 on the first failure.
"""

import argparse
import json
import math
import pathlib
import re
import sys

import cantools
import numpy as np
from asammdf import MDF
from asammdf.blocks import v4_constants as v4c
from mcap.reader import make_reader

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from check_mcap import candump_error_frames, candump_frames, frames_by_message  # noqa: E402  (the same independent parsers)

PARTS = ["BusChannel", "ID", "IDE", "DLC", "DataLength", "DataBytes"]


def fail(msg):
    print(f"check_mf4: FAIL: {msg}")
    sys.exit(1)


def start_ns(mdf):
    t = mdf.header.start_time  # aware datetime, µs resolution
    return (int(t.timestamp()) * 1_000_000 + t.microsecond) * 1000


def can_group(mdf):
    found = [
        i
        for i, g in enumerate(mdf.groups)
        if g.channel_group.flags & v4c.FLAG_CG_BUS_EVENT
        and g.channel_group.acq_source is not None
        and g.channel_group.acq_source.bus_type == v4c.BUS_TYPE_CAN
        and "CAN_DataFrame" in [c.name for c in g.channels]
    ]
    if len(found) != 1:
        fail(f"{len(found)} CAN bus-logging channel groups (bus event flag, CAN source), want 1")
    return found[0]


def check_error_frames(mdf, t0, run_dir):
    """The CAN_ErrorFrame group against candump's error frames: one record each, in order, same
    classes and detail bytes, same time (±1 µs); the ASAM error type named, a protocol violation
    in the CRC sequence or delimiter a CRC error (4). No group where candump logged none."""
    errors = candump_error_frames(run_dir / "candump.log")
    found = [
        i
        for i, g in enumerate(mdf.groups)
        if g.channel_group.flags & v4c.FLAG_CG_BUS_EVENT
        and "CAN_ErrorFrame" in [c.name for c in g.channels]
    ]
    if not errors:
        if found:
            fail("a CAN_ErrorFrame group, but candump.log has no error frame")
        return
    if len(found) != 1:
        fail(f"{len(found)} CAN_ErrorFrame groups for {len(errors)} error frames, want 1")
    gi = found[0]
    got = {p: mdf.get(f"CAN_ErrorFrame.{p}", group=gi, raw=True) for p in ["ErrorClass", "DataBytes", "ErrorType"]}
    times = got["ErrorClass"].timestamps
    if len(times) != len(errors):
        fail(f"the CAN_ErrorFrame group has {len(times)} records, candump.log {len(errors)} error frames")
    for i, e in enumerate(errors):
        if int(got["ErrorClass"].samples[i]) != e["class"] or bytes(got["DataBytes"].samples[i]) != e["data"]:
            fail(f"error frame {i}: classes / bytes differ from candump's {e['class']:x}#{e['data'].hex()}")
        if abs(t0 + round(float(times[i]) * 1e9) - e["t_ns"]) > 1000:
            fail(f"error frame {i}: time differs from candump's {e['t_ns']} ns")
        kind = int(got["ErrorType"].samples[i])
        crc = e["class"] & 0x08 and e["data"][3] in (0x08, 0x18)  # CAN_ERR_PROT, LOC_CRC_SEQ / _DEL
        if kind not in range(6) or (crc and kind != 4):
            fail(f"error frame {i}: ErrorType {kind} for classes {e['class']:x}, location {e['data'][3]:#x}")
    named = mdf.get("CAN_ErrorFrame.ErrorType", group=gi).samples
    print(f"check_mf4: CAN_ErrorFrame: all {len(errors)} error frames of candump.log, classes, bytes and "
          f"times (±1 µs) equal; types {sorted({x.decode() if isinstance(x, bytes) else str(x) for x in named})}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dbc", type=pathlib.Path)
    ap.add_argument("run_dirs", type=pathlib.Path, nargs="+")
    ap.add_argument("--mf4", type=pathlib.Path, help="with one RUN_DIR: its MF4 [default: RUN_DIR/run.mf4]")
    ap.add_argument("--mcap", type=pathlib.Path, help="with one RUN_DIR: its MCAP [default: RUN_DIR/run.mcap]")
    a = ap.parse_args()
    if len(a.run_dirs) > 1 and (a.mf4 or a.mcap):
        fail("--mf4 / --mcap name the files of one RUN_DIR")
    for run_dir in a.run_dirs:
        check(run_dir, a.dbc, a.mf4, a.mcap)


def check(run_dir, dbc, mf4, mcap):
    path = mf4 or run_dir / "run.mf4"
    db = cantools.database.load_file(str(dbc))
    mdf = MDF(str(path))
    if not str(mdf.version).startswith("4.1"):
        fail(f"MDF version {mdf.version}, want 4.1x")
    t0 = start_ns(mdf)
    gi = can_group(mdf)
    names = [c.name for c in mdf.groups[gi].channels]
    for p in PARTS:
        if f"CAN_DataFrame.{p}" not in names:
            fail(f"no CAN_DataFrame.{p} in the CAN group ({names})")
    got = {p: mdf.get(f"CAN_DataFrame.{p}", group=gi, raw=True) for p in PARTS}
    times = got["ID"].timestamps
    print(f"check_mf4: {path}: MDF {mdf.version}, {len(mdf.groups)} groups, start {mdf.header.start_time}")

    frames = candump_frames(run_dir / "candump.log")
    if len(times) != len(frames):
        fail(f"the CAN group has {len(times)} frames, candump.log {len(frames)}")
    for i, fr in enumerate(frames):
        n = len(fr["data"])
        ident = int(got["ID"].samples[i])
        ide = bool(got["IDE"].samples[i])
        data = bytes(got["DataBytes"].samples[i][:n])
        if ident != fr["id"] or ide != fr["extended"] or int(got["DataLength"].samples[i]) != n \
                or int(got["DLC"].samples[i]) != n or data != fr["data"]:
            fail(f"frame {i}: {ident:x} ide {ide} #{data.hex()} is not candump's {fr['id']:x}#{fr['data'].hex()}")
        t = t0 + round(float(times[i]) * 1e9)
        if abs(t - fr["t_ns"]) > 1000:
            fail(f"frame {i}: time {t} vs candump {fr['t_ns']} ns")
    print(f"check_mf4: CAN_DataFrame: all {len(frames)} frames of candump.log, bytes and times (±1 µs) equal")

    check_error_frames(mdf, t0, run_dir)

    at = mdf.groups[gi].channels[names.index("CAN_DataFrame")].attachment
    if at is None:
        fail("no database attached to CAN_DataFrame")
    data, at_name, _ = mdf.extract_attachment(index=at)
    if pathlib.Path(at_name).suffix.lower() != ".dbc" or data != dbc.read_bytes():
        fail(f"the attachment {at_name} is not {dbc}")
    print(f"check_mf4: {at_name} attached to CAN_DataFrame, equal to {dbc}")

    # asammdf's own bus-logging decode against cantools' of the same frames.
    by_id = {m.frame_id: frs for m, frs in frames_by_message(db, frames)}
    out = mdf.extract_bus_logging({"CAN": [(str(dbc), 0)]}, ignore_value2text_conversion=True)
    decoded_groups = {}
    for i, g in enumerate(out.groups):
        m = re.search(r"ID=0x([0-9A-Fa-f]+)", g.channel_group.acq_name or "")
        if m:
            decoded_groups[int(m.group(1), 16)] = i
    values = 0
    for ident, frs in sorted(by_id.items()):
        msg = db.get_message_by_frame_id(ident)
        if ident not in decoded_groups:
            fail(f"extract_bus_logging decoded no {msg.name} (0x{ident:x}); {len(frs)} frames on the bus")
        g = decoded_groups[ident]
        ref = [msg.decode(f["data"], decode_choices=False, scaling=True) for f in frs]
        ref_raw = [msg.decode(f["data"], decode_choices=False, scaling=False) for f in frs]
        t_want = np.array([f["t_ns"] for f in frs], dtype=np.int64)
        for sig in msg.signals:
            # A signal with a value table reads as its names through asammdf's conversion: its
            # raw value is compared with cantools' raw one; every other signal's physical value.
            named = bool(sig.choices)
            s = out.get(sig.name, group=g, raw=named)
            if len(s.samples) != len(frs):
                fail(f"{msg.name}.{sig.name}: {len(s.samples)} samples, {len(frs)} frames")
            want = np.array([float(r[sig.name]) for r in (ref_raw if named else ref)])
            have = s.samples.astype(np.float64)
            bad = ~np.isclose(have, want, rtol=1e-9, atol=1e-9)
            if bad.any():
                k = int(np.argmax(bad))
                fail(f"{msg.name}.{sig.name} frame {k}: asammdf {have[k]}, cantools {want[k]}")
            t = t0 + np.round(s.timestamps.astype(np.float64) * 1e9).astype(np.int64)
            late = np.abs(t - t_want) > 1000
            if late.any():
                k = int(np.argmax(late))
                fail(f"{msg.name}.{sig.name} frame {k}: time {t[k]} vs candump {t_want[k]} ns")
            values += len(frs)
    print(f"check_mf4: extract_bus_logging: {len(by_id)} DBC messages, {values} signal values equal cantools' decode, times ±1 µs")

    mcap_path = mcap or run_dir / "run.mcap"
    if not mcap_path.exists():
        print("check_mf4: no run.mcap: diagnostics not compared")
        return
    with open(mcap_path, "rb") as f:
        reader = make_reader(f)
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        diag = [(msg.log_time, json.loads(msg.data))
                for _, ch, msg in reader.iter_messages(topics=["/ecu/diagnostics"], log_time_order=False)]
    if not diag:
        print("check_mf4: run.mcap holds no diagnostics: none compared")
        return
    offset = meta["bench"].get("realtime_minus_monotonic_ns")
    if not offset:
        fail("run.mcap has diagnostics but no realtime − monotonic offset")
    offset = int(offset)
    dg = [i for i, g in enumerate(mdf.groups) if "cycle_count" in [c.name for c in g.channels]]
    if len(dg) != 1:
        fail(f"{len(dg)} diagnostics groups (a group with cycle_count), want 1")
    dg = dg[0]
    fields = [k for k, v in diag[0][1].items() if k != "timestamp_ns" and (isinstance(v, (int, float)) or v is None)]
    cols = {}
    for k in fields:
        try:
            cols[k] = mdf.get(k, group=dg, raw=True)
        except Exception as e:  # noqa: BLE001 — the field's absence is the finding
            fail(f"diagnostics field {k} is no channel of the MF4 ({e})")
    n = len(cols["cycle_count"].samples)
    if n != len(diag):
        fail(f"{n} diagnostics records in the MF4, {len(diag)} in run.mcap")
    t = t0 + np.round(cols["cycle_count"].timestamps.astype(np.float64) * 1e9).astype(np.int64)
    # One clock: a bench run's MCAP log times are UTC, as the MF4's are (older files: on the
    # bench's CLOCK_MONOTONIC, the offset added here).
    utc = "UTC" in meta["bench"].get("log_time_clock", "")
    t_want = np.array([lt if utc else lt + offset for lt, _ in diag], dtype=np.int64)
    off = np.abs(t - t_want) > 1000
    if off.any():
        i = int(np.argmax(off))
        fail(f"diagnostics {i}: MF4 time {t[i]} vs the MCAP's UTC log time {t_want[i]} ns")
    for k in fields:
        have = cols[k].samples
        if np.issubdtype(have.dtype, np.floating):
            # JSON carries NaN as null; a float32 field's shortest decimal reads back exactly.
            want = np.array([np.nan if r[k] is None else r[k] for _, r in diag]).astype(have.dtype)
            bad = ~((have == want) | (np.isnan(have) & np.isnan(want)))
        else:
            if any(r[k] is None for _, r in diag):
                fail(f"diagnostics field {k}: null in run.mcap, an integer channel in the MF4")
            want = np.array([r[k] for _, r in diag], dtype=np.uint64)
            bad = have.astype(np.uint64) != want
        if bad.any():
            i = int(np.argmax(bad))
            fail(f"diagnostics {i}.{k}: {have[i]}, MCAP {diag[i][1][k]}")
    print(f"check_mf4: EcuDiagnostics: all {n} records of run.mcap, {len(fields)} fields each, equal; times ±1 µs")


if __name__ == "__main__":
    main()
