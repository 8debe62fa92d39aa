#!/usr/bin/env python3
"""Independent side of the real-bus test: python-cantools with bus/restraint.dbc.

  cantools_check.py decode DBC CANDUMP_LOG   -> JSON list of decoded frames (stdout)
  cantools_check.py encode DBC REQUESTS_JSON -> one `ID#HEX` line per request (stdout)

The E2E CRC is computed here with a bitwise CRC-8 SAE J1850 (poly 0x1D, init 0xFF, xor 0xFF)
over the data id (low byte, high byte, from the DBC attribute E2EDataId) and the payload bytes
except byte 0, written independently of the Rust code it checks.
"""
import json
import sys

import cantools


def crc8_j1850(data: bytes) -> int:
    crc = 0xFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


assert crc8_j1850(b"123456789") == 0x4B  # published check value


def data_id(msg):
    attr = msg.dbc.attributes.get("E2EDataId") if msg.dbc else None
    return attr.value if attr is not None and attr.value else None


def e2e_crc(msg, payload: bytes) -> int:
    did = data_id(msg)
    return crc8_j1850(bytes([did & 0xFF, did >> 8]) + payload[1:])


def decode(db, log_path):
    out = []
    with open(log_path) as f:
        for line in f:
            parts = line.split()
            if len(parts) < 3 or "#" not in parts[2]:
                continue
            ident, hexdata = parts[2].split("#", 1)
            frame_id = int(ident, 16)
            payload = bytes.fromhex(hexdata)
            try:
                msg = db.get_message_by_frame_id(frame_id)
            except KeyError:
                out.append({"id": frame_id, "name": None})
                continue
            sigs = msg.decode(payload, decode_choices=False, scaling=True)
            rec = {"id": frame_id, "name": msg.name, "signals": {k: float(v) for k, v in sigs.items()}}
            if data_id(msg) is not None:
                rec["crc_ok"] = e2e_crc(msg, payload) == payload[0]
            out.append(rec)
    json.dump(out, sys.stdout)


def encode(db, req_path):
    with open(req_path) as f:
        reqs = json.load(f)
    for r in reqs:
        msg = db.get_message_by_name(r["name"])
        sigs = dict(r["signals"])
        payload = bytearray(msg.encode(sigs, scaling=True, strict=True))
        if data_id(msg) is not None:
            sigs["Crc"] = e2e_crc(msg, bytes(payload))
            payload = bytearray(msg.encode(sigs, scaling=True, strict=True))
        print(f"{msg.frame_id:03X}#{payload.hex().upper()}")


def main():
    cmd, dbc, path = sys.argv[1:4]
    db = cantools.database.load_file(dbc)
    {"decode": decode, "encode": encode}[cmd](db, path)


if __name__ == "__main__":
    main()
