"""The kitting cell's campaign (the paper's 90 trials, 15 per class, as 15 kits of one part
of each class): the simulated cell of launch/kitting_sim.launch, headless, with its own ROS
master on a free port, fed kit by kit by kitting_trials. Shows a progress bar and one line
per part, then the per-class table (detection, classification, pick, place, pose error).

Writes bench/results/<name>.json (success_rate, kit score (ARIAC's kitting score, summed
over the kits), misses (parts that rode off the belt unpicked), pose_error_mm_p50/p95 =
belt-plane distance between each vision pose and the simulator's true pose at the image's
stamp, picks_per_minute, arrival rate, spawn-to-place times, physics real-time factor,
per-class table, every part and kit, where the pick cycle goes: cycle_phases_s, each
phase's p50/mean/p95 over the placing picks) and bench/results/<name>_confusion.png. The
session's full log goes to bench/results/<name>.log. A run that ends without a summary
writes nothing.

--feed continuous --rate R puts a part on the belt every 60/R s, several at once.
--rates R1,R2,... runs one continuous campaign per rate and draws the busy-belt curve
(success, picks/min and misses against the arrival rate) into bench/results/kitting_belt.png
with bench/results/kitting_belt.json (the highest rate with >= 99 % success).

Run: bench/run kitting_campaign [--trials 90] [--seed N] [--perturb] [--kit-order FILE]
     [--feed continuous --rate 6 | --rates 3,4,5,6,7 [--curve-only]] [--ur-fake] [--name NAME]
"""

import argparse
import glob
import io
import json
import math
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time

from bench_common import RESULTS, ROOT, write_results
from motion_common.atomic_file import write_atomic

LAUNCH = os.path.join(ROOT, "src", "motion_bringup", "launch", "kitting_sim.launch")
RUN_SESSION = os.path.join(ROOT, "scripts", "run_session")
CLASSES = ("bolt_yellow", "bolt_silver", "nut_yellow", "nut_silver", "washer_yellow", "washer_silver")
HEADLINE = (
    "trials",
    "success_rate",
    "kit_score_rate",
    "kits_complete",
    "kits",
    "misses",
    "pose_error_mm_p50",
    "pose_error_mm_p95",
    "picks_per_minute",
    "arrival_rate_per_min",
    "spawn_to_place_s_p50",
    "spawn_to_place_s_p99",
    "physics_real_time_factor_min",
    "physics_real_time_factor_mean",
    "unverified_picks",
    "wall_time_s",
)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("localhost", 0))
        return probe.getsockname()[1]


def run_campaign(args, feed: str, rate: float, name: str) -> dict | None:
    """One session; its summary (also written as bench/results/<name>.json), or None."""
    output = tempfile.mkdtemp(prefix="kitting-campaign-")
    log_path = os.path.join(RESULTS, f"{name}.log")
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{free_port()}")
    command = [
        sys.executable,
        RUN_SESSION,
        "--monitor",
        "kitting_trials",
        LAUNCH,
        f"trials:={args.trials}",
        f"seed:={args.seed}",
        f"perturb:={'true' if args.perturb else 'false'}",
        f"robot:={args.robot}",
        f"output_dir:={output}",
        "required_trials:=false",
        f"feed:={feed}",
        f"rate:={rate}",
    ]
    if args.kit_order:
        command.append(f"kit_order:={os.path.abspath(args.kit_order)}")
    if args.ur_fake:
        command.append("ur_fake:=true")
    print(
        f"kitting campaign: {args.trials} parts, seed {args.seed}, perturb {args.perturb}, feed {feed}"
        + (f" at {rate:g} parts/min" if feed == "continuous" else "")
        + f", master {env['ROS_MASTER_URI']}; log {log_path}",
        flush=True,
    )
    started = time.monotonic()
    with open(log_path, "w", encoding="utf-8") as log:
        process = subprocess.Popen(
            command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1
        )
        try:
            for line in process.stdout:
                log.write(line)
                # The trials' own lines (progress bar, kits, table, summary) go to the screen.
                if line.startswith(
                    ("[#", "[ ", "kitting_trials", "class ", "success ", "cycle ", "  failed", "  kit ")
                ) or (line.split(" ")[0] in CLASSES):
                    print(line, end="", flush=True)
            code = process.wait()
        except KeyboardInterrupt:
            process.terminate()
            process.wait()
            print("campaign interrupted", file=sys.stderr)
            raise
    wall = time.monotonic() - started
    # The session writes into its own run folder under output_dir.
    found = sorted(glob.glob(os.path.join(output, "**", "kitting_summary.json"), recursive=True))
    if not found:
        print(f"the session ended (code {code}) without a summary; see {log_path}", file=sys.stderr)
        shutil.rmtree(output, ignore_errors=True)
        return None
    with open(found[-1], encoding="utf-8") as stream:
        summary = json.load(stream)
    confusion = os.path.join(os.path.dirname(found[-1]), "kitting_confusion.png")
    if os.path.isfile(confusion):
        with open(confusion, "rb") as stream:
            write_atomic(os.path.join(RESULTS, f"{name}_confusion.png"), stream.read())
    shutil.rmtree(output, ignore_errors=True)
    summary.update(wall_time_s=wall, command=" ".join(["bench/run kitting_campaign"] + sys.argv[1:]))
    write_results(name, summary, show=False)
    print(json.dumps({k: summary[k] for k in HEADLINE if k in summary}, indent=2, default=float))
    return summary


def belt_curve(rows: list[dict], path: str):
    """Success, picks/min and misses against the arrival rate (PNG, atomically)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rates = [r["rate"] for r in rows]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    top.plot(rates, [100 * r["success_rate"] for r in rows], "o-", label="success (placed in its slot)")
    top.axhline(99, color="grey", linestyle=":", label="99 %")
    top.set_ylabel("success, %")
    top.legend(loc="lower left")
    bottom.plot(rates, [r["picks_per_minute"] for r in rows], "s-", label="picks / min (placed)")
    bottom.plot(rates, rates, color="grey", linestyle=":", label="arrival rate")
    bottom.bar(rates, [r["misses"] for r in rows], width=0.2, alpha=0.4, color="C3", label="misses (parts)")
    bottom.set_xlabel("arrival rate, parts / min")
    bottom.set_ylabel("picks / min; misses")
    bottom.legend(loc="upper left")
    top.set_title("kitting cell, busy belt (default belt speed)")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    write_atomic(path, buffer.getvalue())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--trials",
        type=int,
        default=90,
        help="parts fed, as kits of one part of each class (default 90 = 15 kits, 15 per class, as in the paper)",
    )
    parser.add_argument("--seed", type=int, default=1, help="random seed of order, positions, perturbations")
    parser.add_argument(
        "--perturb",
        action="store_true",
        help="vary lighting, camera pose (±2 cm / ±2°, then "
        "re-registered from the markers), belt speed (±30 %%, one part at a time only) and part orientation",
    )
    parser.add_argument("--robot", default="ur10e", choices=("ur10e", "ur5e"), help="robot model")
    parser.add_argument("--kit-order", default="", help="kit order YAML (then --trials is ignored)")
    parser.add_argument("--feed", default="one_at_a_time", choices=("one_at_a_time", "continuous"))
    parser.add_argument("--rate", type=float, default=4.0, help="parts per minute with --feed continuous")
    parser.add_argument("--rates", default="", help="comma-separated rates (parts/min): the busy-belt curve")
    parser.add_argument(
        "--curve-only",
        action="store_true",
        help="with --rates: draw the curve from the runs already in bench/results/<name>_<rate>.json",
    )
    parser.add_argument("--ur-fake", action="store_true", help="the UR driver on its simulated controller")
    parser.add_argument("--name", default="", help="results name (default kitting_campaign, kitting_belt_<rate>)")
    args = parser.parse_args(argv)
    if args.trials < 1:
        parser.error("--trials must be at least 1")
    os.makedirs(RESULTS, exist_ok=True)
    try:
        if not args.rates:
            default = "kitting_campaign" if args.feed == "one_at_a_time" else f"kitting_belt_{args.rate:g}"
            summary = run_campaign(args, args.feed, args.rate, args.name or default)
            if summary is None:
                return 2
            return 0 if summary.get("success_rate") == 1.0 else 1
        rates = sorted(float(r) for r in args.rates.split(","))
        rows = []
        for rate in rates:
            name = f"{args.name or 'kitting_belt'}_{rate:g}"
            if args.curve_only:
                path = os.path.join(RESULTS, f"{name}.json")
                summary = json.load(open(path, encoding="utf-8")) if os.path.isfile(path) else None
            else:
                summary = run_campaign(args, "continuous", rate, name)
            if summary is None:
                continue
            rows.append(
                {
                    "rate": rate,
                    "arrival_rate_per_min": summary.get("arrival_rate_per_min"),
                    "success_rate": summary["success_rate"],
                    "picks_per_minute": summary["picks_per_minute"],
                    "misses": summary["misses"],
                    "trials": summary["trials"],
                    "kit_score_rate": summary.get("kit_score_rate"),
                    "cycle_s_p50": summary.get("cycle_phases_s", {}).get("cycle", {}).get("p50"),
                    "failures": [f["reason"] or f["state"] for f in summary["failures"]],
                }
            )
    except KeyboardInterrupt:
        return 130
    if not rows:
        print("no busy-belt run ended with a summary: nothing written", file=sys.stderr)
        return 2
    good = [r["rate"] for r in rows if r["success_rate"] >= 0.99]
    result = {
        "rows": rows,
        "highest_rate_99_percent": max(good) if good else math.nan,
        "seed": args.seed,
        "trials_per_rate": args.trials,
        "command": " ".join(["bench/run kitting_campaign"] + (argv or sys.argv[1:])),
    }
    name = args.name or "kitting_belt"
    write_results(name, result, show=False)
    belt_curve(rows, os.path.join(RESULTS, f"{name}.png"))
    for r in rows:
        print(
            f"rate {r['rate']:4.1f}/min: success {100 * r['success_rate']:5.1f} %, "
            f"{r['picks_per_minute']:.2f} picks/min, {r['misses']} misses"
        )
    print(f"highest rate with >= 99 % success: {result['highest_rate_99_percent']} parts/min")
    print(f"written: {os.path.join(RESULTS, name + '.json')}, {os.path.join(RESULTS, name + '.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
