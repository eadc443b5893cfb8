"""The kitting cell's campaign (the paper's 90 trials, 15 per class): the simulated cell of
launch/kitting_sim.launch, headless, with its own ROS master on a free port, fed one part
per trial by kitting_trials. Shows a progress bar and one line per trial, then the
per-class table (detection, classification, pick, place, pose error).

Writes bench/results/kitting_campaign.json (success_rate, pose_error_mm_p50/p95 = belt-plane
distance between each vision pose and the simulator's true pose at the image's stamp,
picks_per_minute, spawn-to-place times, physics real-time factor, per-class table, every
trial) and bench/results/kitting_campaign_confusion.png. The session's full log goes to
bench/results/kitting_campaign.log.

Run: bench/run kitting_campaign [--trials 90] [--seed N] [--perturb]
"""

import argparse
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time

from bench_common import RESULTS, ROOT, write_results

LAUNCH = os.path.join(ROOT, "src", "motion_bringup", "launch", "kitting_sim.launch")
RUN_SESSION = os.path.join(ROOT, "scripts", "run_session")


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("localhost", 0))
        return probe.getsockname()[1]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--trials",
        type=int,
        default=90,
        help="number of trials, cycling through the six classes (default 90 = 15 per class, as in the paper)",
    )
    parser.add_argument("--seed", type=int, default=1, help="random seed of positions, orientations, perturbations")
    parser.add_argument(
        "--perturb",
        action="store_true",
        help="vary lighting, camera pose (±2 cm / ±2°, then "
        "re-registered from the markers), belt speed (±30 %%) and part orientation per trial",
    )
    parser.add_argument("--robot", default="ur10e", choices=("ur10e", "ur5e"), help="robot model")
    args = parser.parse_args(argv)
    if args.trials < 1:
        parser.error("--trials must be at least 1")
    os.makedirs(RESULTS, exist_ok=True)
    output = tempfile.mkdtemp(prefix="kitting-campaign-")
    log_path = os.path.join(RESULTS, "kitting_campaign.log")
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
    ]
    print(
        f"kitting campaign: {args.trials} trials, seed {args.seed}, perturb {args.perturb}, "
        f"master {env['ROS_MASTER_URI']}; log {log_path}",
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
                # The trials' own lines (progress bar, table, summary) go to the screen.
                if line.startswith(("[#", "[ ", "kitting_trials", "class ", "success ", "  failed")) or line.split(" ")[
                    0
                ] in ("bolt_yellow", "bolt_silver", "nut_yellow", "nut_silver", "washer_yellow", "washer_silver"):
                    print(line, end="", flush=True)
            code = process.wait()
        except KeyboardInterrupt:
            process.terminate()
            process.wait()
            print("campaign interrupted", file=sys.stderr)
            return 130
    wall = time.monotonic() - started
    summary_path = os.path.join(output, "kitting_summary.json")
    if not os.path.isfile(summary_path):
        print(f"the session ended (code {code}) without a summary; see {log_path}", file=sys.stderr)
        return 2
    with open(summary_path, encoding="utf-8") as stream:
        summary = json.load(stream)
    shutil.copyfile(
        os.path.join(output, "kitting_confusion.png"), os.path.join(RESULTS, "kitting_campaign_confusion.png")
    )
    shutil.rmtree(output, ignore_errors=True)
    summary.update(wall_time_s=wall, command=" ".join(["bench/run kitting_campaign"] + (argv or sys.argv[1:])))
    headline = {
        k: summary[k]
        for k in (
            "trials",
            "success_rate",
            "pose_error_mm_p50",
            "pose_error_mm_p95",
            "picks_per_minute",
            "spawn_to_place_s_p50",
            "spawn_to_place_s_p99",
            "physics_real_time_factor_min",
            "physics_real_time_factor_mean",
            "unverified_picks",
            "wall_time_s",
        )
        if k in summary
    }
    write_results("kitting_campaign", summary, show=False)
    print(json.dumps(headline, indent=2))
    print(f"confusion matrix: {os.path.join(RESULTS, 'kitting_campaign_confusion.png')}")
    return 0 if summary.get("success_rate") == 1.0 else 1


if __name__ == "__main__":
    sys.exit(main())
