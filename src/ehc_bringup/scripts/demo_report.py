#!/usr/bin/python3
"""Summary lines, JSON summary and PNG plot of a `make demo` run (demo.sh).

demo_report.py SUMMARY_JSON TRACE_CSV OUT_PNG [--controller-config YAML] [--wall SECONDS]

Reads the grasp sequencer's summary.json and trace.csv (one row per control cycle), adds the
controller settings (mode, MPBS on/off) and the wall time to summary.json, prints one line per
object and the JSON, and plots |e|, sig(omega), base and arm speeds over sim time with the
object phases shaded.
"""
import argparse
import os
import csv
import json
import sys


def mpbs_enabled(path):
    """mpbs.enabled of the controller YAML, following its `extends:` chain (as ConfigNode does);
    None when no file of the chain has an mpbs section."""
    try:
        import yaml
        for _ in range(8):
            with open(path) as f:
                cfg = yaml.safe_load(f) or {}
            m = cfg.get("mpbs")
            if isinstance(m, dict) and "enabled" in m:
                return bool(m["enabled"])
            base = cfg.get("extends")
            if not base:
                return True if isinstance(m, dict) else None
            path = os.path.join(os.path.dirname(path), base)
    except Exception:  # noqa: BLE001 - the report must not fail on this
        return None
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("summary")
    ap.add_argument("trace")
    ap.add_argument("png")
    ap.add_argument("--controller-config", default="")
    ap.add_argument("--wall", type=float, default=None)
    ap.add_argument("--mpbs", choices=["true", "false"], default=None, help="the controller's _mpbs override")
    a = ap.parse_args()

    with open(a.summary) as f:
        s = json.load(f)
    if a.controller_config:
        s["controller_config"] = a.controller_config
        s["mpbs"] = mpbs_enabled(a.controller_config)
    if a.mpbs is not None:
        s["mpbs"] = a.mpbs == "true"
    if a.wall is not None:
        s["wall_time_s"] = a.wall
    with open(a.summary, "w") as f:
        json.dump(s, f, indent=1)
        f.write("\n")

    for o in s["objects"]:
        line = ("%-8s %-7s time %6.2f s  TfM %5.1f %% (at a distance; %5.1f %% to the pre-grasp switch, %5.1f %% to the "
                "gripper closing)  %s grasp from %s") % (
            o["name"], "SUCCESS" if o["success"] else "FAILED", o["time_s"], 100.0 * o["tfm"],
            100.0 * o.get("tfm_until_switch", 0.0), 100.0 * o.get("tfm_until_close", 0.0), o["approach"],
            "perception candidate" if o["grasp_from_candidate"] else "tag target")
        if o.get("close_offset_m", -1.0) >= 0.0:
            line += "  closed %.1f mm from the grasp" % (1000.0 * o["close_offset_m"])
        if not o["success"]:
            line += "  [%s: %s]" % (o["failed_phase"], o["reason"])
        print(line)
    print("%d/%d grasped, sim time %.1f s, mode %s, MPBS %s" % (
        s["successes"], s["objects_total"], s["total_time_s"], s["mode"],
        {True: "on", False: "off", None: "n/a (controller without MPBS)"}[s.get("mpbs")]))
    print(json.dumps({"objects": [{k: o[k] for k in ("name", "success", "time_s", "tfm")} for o in s["objects"]],
                      "successes": s["successes"], "mode": s["mode"], "mpbs": s.get("mpbs")}))

    rows = []
    try:
        with open(a.trace) as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        print("demo_report: no trace (%s): no plot" % e, file=sys.stderr)
        return 0
    if not rows:
        print("demo_report: empty trace: no plot", file=sys.stderr)
        return 0
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t0 = float(rows[0]["t"])
    t = [float(r["t"]) - t0 for r in rows]
    col = lambda k: [float(r[k]) for r in rows]  # noqa: E731
    fig, ax = plt.subplots(3, 1, figsize=(10, 8), sharex=True)
    ax[0].plot(t, col("error_norm"), label="|e| (m + rad)")
    ax[0].plot(t, col("position_error"), label="position error (m)", alpha=0.7)
    ax[0].set_ylabel("error")
    ax[0].legend(loc="upper right")
    ax[1].plot(t, col("sig_omega"), color="tab:green")
    ax[1].set_ylabel("sig(omega)")
    ax[1].set_ylim(-0.05, 1.05)
    ax[2].plot(t, col("base_speed"), label="base linear (m/s)")
    ax[2].plot(t, col("base_turn_rate"), label="base turn (rad/s)")
    ax[2].plot(t, col("arm_speed"), label="arm |qdot| (rad/s)")
    ax[2].set_ylabel("speed")
    ax[2].set_xlabel("sim time (s)")
    ax[2].legend(loc="upper right")
    # Shade each object's span and mark its name.
    start, name = 0, rows[0]["object"]
    colors = ["#f0f0ff", "#f0fff0", "#fff0f0"]
    k = 0
    for i in range(1, len(rows) + 1):
        if i == len(rows) or rows[i]["object"] != name:
            for x in ax:
                x.axvspan(t[start], t[i - 1], color=colors[k % 3], zorder=0)
            ax[0].text(t[start], ax[0].get_ylim()[1] * 0.9, " " + name, fontsize=9)
            k += 1
            if i < len(rows):
                start, name = i, rows[i]["object"]
    fig.suptitle("EHC-MM demo: %d/%d grasped (mode %s, MPBS %s)" % (
        s["successes"], s["objects_total"], s["mode"], {True: "on", False: "off", None: "n/a"}[s.get("mpbs")]))
    fig.tight_layout()
    fig.savefig(a.png, dpi=90)
    print("plot: %s, summary: %s" % (a.png, a.summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
