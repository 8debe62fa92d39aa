#!/usr/bin/env python3
"""Keep the restraint ECU's CAN inputs alive from Python: python-can sends, cantools encodes.

Sends EgoVehicleState (0x0A0) and OccupantClassification (0x0C0) at the DBC's cycle times
(GenMsgCycleTime: 10 ms and 100 ms), each with the E2E protection the ECU checks on every input
frame: a CRC-8 in byte 0 and a 4-bit alive counter that steps by one per frame. A frame without
them is rejected (`e2e:crc_mismatch`, `counter_skipped`), so `cansend` of a hand-typed payload is
not enough; this script is the recipe for any other sender.

The E2E protection (bus/README.md, "E2E protection"):
  * AliveCounter: 0, 1, … 15, 0, … per message, one step per frame sent;
  * Crc: CRC-8 SAE J1850 (polynomial 0x1D, initial value 0xFF, final XOR 0xFF) over the
    message's E2EDataId (a DBC attribute; low byte first, then the high byte) followed by the
    payload's bytes 1..7 (everything but the CRC byte itself), the counter already in place.

Usage (the venv the set-up makes has python-can and cantools):

    target/pyenv/bin/python3 examples/python/keep_inputs_alive.py --can vcan0 --duration-s 10

With the ECU running on the same interface (`ecu --can vcan0`), its report counts every frame
as accepted (`can_accepted`, no `can_rejected_*`) and EcuStatus.FaultVehicleInput /
FaultOccupantInput stay clear. The values are a belted mid-size adult at 300 mm from the wheel,
in a car driving at `--ego-speed-kph`; change them in `inputs()`.
"""
import argparse
import os
import pathlib
import sys
import time

import can
import cantools

REPO = pathlib.Path(__file__).resolve().parents[2]


def crc8_sae_j1850(data: bytes) -> int:
    """CRC-8 SAE J1850: polynomial 0x1D, initial value 0xFF, final XOR 0xFF."""
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


assert crc8_sae_j1850(b"123456789") == 0x4B  # the algorithm's published check value


class E2eSender:
    """One protected message: encodes its signals with the next alive counter and the CRC."""

    def __init__(self, msg: cantools.database.Message):
        self.msg = msg
        self.data_id = msg.dbc.attributes["E2EDataId"].value
        self.cycle_s = msg.cycle_time / 1000.0
        self.counter = 0

    def frame(self, signals: dict) -> can.Message:
        sigs = dict(signals, AliveCounter=self.counter, Crc=0)
        payload = self.msg.encode(sigs, scaling=True, strict=True)
        did = bytes([self.data_id & 0xFF, self.data_id >> 8])
        sigs["Crc"] = crc8_sae_j1850(did + payload[1:])
        payload = self.msg.encode(sigs, scaling=True, strict=True)
        self.counter = (self.counter + 1) % 16
        return can.Message(arbitration_id=self.msg.frame_id, data=payload, is_extended_id=False)


def inputs(speed_kph: float) -> dict:
    """The signals each message carries (physical values in the DBC's units, or value names)."""
    return {
        "EgoVehicleState": {
            "BrakeState": "Released",
            "EgoSpeed": speed_kph / 3.6,
            "EgoLongAccel": 0.0,
        },
        "OccupantClassification": {
            "BeltBuckle": "Buckled",
            "OccupantClass": "MidAdult",
            "ClassConfidence": 95,
            "OccupantMass": 75.0,
            "ChestToWheel": 300,
            "SeatTrackPosition": 200,
        },
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--can", default=os.environ.get("VCAN", "vcan0"), help="SocketCAN interface (default $VCAN or vcan0)")
    ap.add_argument("--dbc", default=str(REPO / "bus" / "restraint.dbc"), help="the bus's DBC (default: the repository's)")
    ap.add_argument("--duration-s", type=float, default=10.0, help="how long to send, s (default 10)")
    ap.add_argument("--ego-speed-kph", type=float, default=50.0, help="the ego speed sent, km/h (default 50)")
    args = ap.parse_args()

    db = cantools.database.load_file(args.dbc)
    signals = inputs(args.ego_speed_kph)
    senders = [E2eSender(db.get_message_by_name(name)) for name in signals]
    sent = {s.msg.name: 0 for s in senders}
    try:
        bus = can.Bus(interface="socketcan", channel=args.can)
    except (OSError, can.CanError) as e:
        print(f"keep_inputs_alive: error: cannot open {args.can}: {e}", file=sys.stderr)
        return 2
    with bus:
        start = time.monotonic()
        due = [start] * len(senders)
        while True:
            now = time.monotonic()
            if now - start >= args.duration_s:
                break
            for k, s in enumerate(senders):
                if now >= due[k]:
                    bus.send(s.frame(signals[s.msg.name]))
                    sent[s.msg.name] += 1
                    # On the cycle's grid, not from now: the ECU's timeout counts the gaps.
                    due[k] += s.cycle_s
            time.sleep(max(0.0, min(due) - time.monotonic()))
    print(", ".join(f"{name}: {n} frames" for name, n in sent.items()) + f" on {args.can}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
