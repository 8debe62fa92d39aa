#!/usr/bin/env python3
"""A run's recording as one picture, read with Foxglove's `mcap` package alone (no project
code): what the Foxglove layout record/foxglove-layout.json shows, for where Foxglove cannot run.

    plot_mcap.py RUN.mcap OUT.png

Panels, all on the recording's one clock (ms after the true contact when the file names it):
  1. the ECU's mode (diagnostics) as a state timeline, with the EcuStatus mode from the bus;
  2. the estimate: closing speed ± σ and time to contact (diagnostics), the true closing speed;
  3. planned fire times on the bus (AirbagStageCmd.FireTime, BeltLimiterCmd.PretensionerFireTime)
     and the stubs' actions (airbag / pretensioner fired);
  4. the predicted pulse the ECU held at the end of pre-crash (/ecu/predicted_pulse);
  5. frames per 100 ms on the bus, by message.
"""

import collections
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mcap.reader import make_reader  # noqa: E402


def main():
    path, out = sys.argv[1], sys.argv[2]
    topics = collections.defaultdict(list)
    with open(path, "rb") as f:
        r = make_reader(f)
        meta = {m.name: m.metadata for m in r.iter_metadata()}
        for _, ch, m in r.iter_messages():
            topics[ch.topic].append((m.log_time, json.loads(m.data)))
    bench = meta.get("bench", {})
    # The contact is a bench (CLOCK_MONOTONIC) time; log times are UTC where the file says so.
    shift = int(bench.get("realtime_minus_monotonic_ns") or 0) if "UTC" in bench.get("log_time_clock", "") else 0
    t0 = (int(bench.get("contact_ns") or 0) + shift if bench.get("contact_ns") not in (None, "", "0") else 0) or (topics["/can/raw"][0][0] if topics["/can/raw"] else 0)
    rel = "ms after the true contact" if bench.get("contact_ns") not in (None, "", "0") else "ms after the first frame"
    ms = lambda t: (t - t0) / 1e6  # noqa: E731

    diag = topics["/ecu/diagnostics"]
    fig, ax = plt.subplots(5, 1, figsize=(11, 13), sharex=False)
    title = f"{bench.get('scenario', path)} — route {bench.get('route', '?')}, timing {bench.get('timing', '?').split(' (')[0]}"
    fig.suptitle(title, fontsize=12)

    # 1. modes
    modes = [(ms(t), d["mode_name"]) for t, d in diag]
    names = sorted({m for _, m in modes}, key=lambda n: [m for _, m in modes].index(n))
    ax[0].step([t for t, _ in modes], [names.index(m) for _, m in modes], where="post", label="diagnostics mode")
    ax[0].set_yticks(range(len(names)), names)
    status = [(ms(t), v.get("EcuMode")) for t, v in topics["/can/EcuStatus"]]
    if status:
        ax2 = ax[0].twinx()
        ax2.step([t for t, _ in status], [v for _, v in status], where="post", color="tab:orange", alpha=0.6, label="EcuStatus.EcuMode (bus)")
        ax2.set_ylabel("EcuStatus.EcuMode (raw)")
    ax[0].set_title("ECU mode: diagnostics (steps) and EcuStatus on the bus (orange)")

    # 2. estimate
    pts = [(ms(t), d["closing_speed_mps"], d["closing_speed_sigma_mps"], d["time_to_contact_s"]) for t, d in diag if d.get("closing_speed_mps") is not None]
    if pts:
        t, v, s, ttc = zip(*pts)
        s = [x if x is not None else 0.0 for x in s]
        ax[1].plot(t, v, label="closing speed [m/s]")
        truth = [(ms(tt), d["closing_speed_mps"]) for tt, d in topics["/truth/world"] if ms(tt) < 0]
        if truth:
            ax[1].plot(*zip(*truth), "k--", lw=0.8, label="true closing speed before contact (/truth/world)")
        ax[1].fill_between(t, [a - b for a, b in zip(v, s)], [a + b for a, b in zip(v, s)], alpha=0.3, label="± σ")
        ax1b = ax[1].twinx()
        ax1b.plot(t, [x if x is not None else float("nan") for x in ttc], color="tab:green", label="time to contact [s]")
        ax1b.set_ylabel("time to contact [s]")
        ax[1].legend(loc="upper left")
    ax[1].set_title("ECU estimate (diagnostics)")

    # 3. planned fire times and actions
    bag = [(ms(t), v["FireTime"]) for t, v in topics["/can/AirbagStageCmd"]]
    pre = [(ms(t), v["PretensionerFireTime"]) for t, v in topics["/can/BeltLimiterCmd"]]
    if bag:
        ax[2].plot(*zip(*bag), ".", ms=2, label="AirbagStageCmd.FireTime [ms]")
    if pre:
        ax[2].plot(*zip(*pre), ".", ms=2, label="BeltLimiterCmd.PretensionerFireTime [ms]")
    for t, a in topics["/stubs/actions"]:
        ax[2].axvline(ms(t), color="red", alpha=0.6)
        ax[2].annotate(a["what"], (ms(t), 0), rotation=90, fontsize=7, color="red")
    ax[2].set_title("planned fire times on the bus; the stubs' actions (red)")
    ax[2].legend(loc="lower left", fontsize=8)

    # 4. predicted pulse of the last record before the crash phase
    pre_crash_until = max((t for t, d in diag if d["mode_name"] == "pre-crash"), default=None)
    pulses = [d for t, d in topics["/ecu/predicted_pulse"] if pre_crash_until is not None and t <= pre_crash_until and d["pulse_points"] > 0]
    if pulses:
        d = pulses[-1]
        n, dt = d["pulse_points"], d["pulse_dt_s"]
        ax[3].plot([i * dt * 1e3 for i in range(n)], [-a / 9.80665 for a in d["pulse_accel_mps2"][:n]],
                   label="predicted (/ecu/predicted_pulse), from the predicted contact")
        span = n * dt * 1e3
    else:
        span = 150.0
    for topic, style in (("/sensors/crash_accel", "tab:red"), ("/sensors/safing_accel", "tab:gray")):
        pts = [(ms(b["first_timestamp_ns"] + k * b["sample_period_ns"]), -a / 9.80665)
               for _, b in topics[topic] for k, a in enumerate(b["accel_mps2"])]
        pts = [p for p in pts if -10.0 <= p[0] <= span]
        if pts:
            ax[3].plot(*zip(*pts), ".", ms=2, color=style, alpha=0.6, label=f"measured ({topic}), from the true contact")
    ax[3].set_xlabel("ms after contact")
    ax[3].set_ylabel("deceleration [g]")
    ax[3].legend(loc="upper right", fontsize=8)
    ax[3].set_title("crash pulse: predicted at the end of pre-crash, and as the accelerometers measured it")

    # 5. bus load
    counts = collections.defaultdict(collections.Counter)
    for t, v in topics["/can/raw"]:
        counts[v["message"] or f"0x{v['id']:x}"][int(ms(t) // 100)] += 1
    for name, c in sorted(counts.items()):
        xs = sorted(c)
        ax[4].step([x * 100 for x in xs], [c[x] for x in xs], label=name, lw=0.8)
    ax[4].legend(fontsize=7, ncol=4)
    ax[4].set_title("frames per 100 ms on the bus, by message (/can/raw)")
    for a in list(ax[:3]) + [ax[4]]:
        a.set_xlabel(rel)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(out, dpi=90)
    print(f"plot_mcap: {out}")


if __name__ == "__main__":
    main()
