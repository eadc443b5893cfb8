"""scripts/record_demo: gesture-taught pick-and-place episodes recorded as one LeRobot
dataset, read back with LeRobot's loader, one replayed; a summary and a picture.

1. ``--episodes`` runs of scripts/teach_sim (the teach demo's stream of real Leap frames),
   each recorded as one episode (dataset:=, the scene camera, the episode starting with the
   robot state and ending with the save gesture, circle); its success is the teach demo's
   verdict (the part placed within its tolerance), marked in the dataset;
2. the dataset read back by LeRobot's own loader (offline): episodes, frames, fps, and the
   camera frames decoded;
3. episode 0 replayed (replay_episode) on a fresh simulated arm (hw_sim.launch with the
   teach scene), its tool error against the recording;
4. record_demo.json (the summary) and record_demo.png (episode 0's camera frames and joint
   traces) in output/runs/record_demo-<date>-<time>/, with the dataset and the logs.

Exit 0 when every episode was saved and read back and the replay ran; the replay's
tolerance (--tolerance-mm) is reported, not enforced (see docs/applications.md).
"""

import argparse
import datetime
import json
import os
import signal
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
for package in ("motion_common", "motion_apps"):
    sys.path.insert(0, os.path.join(ROOT, "src", package))

from motion_apps.dataset_store import DatasetStore  # noqa: E402
from motion_apps.episode_recorder import read_episode_list  # noqa: E402
from motion_apps.episode_report import format_summary, plot_episode, summarize_dataset, velocity_agreement  # noqa: E402
from motion_apps.lerobot_readback import read_dataset  # noqa: E402
from motion_common.atomic_file import write_atomic  # noqa: E402

SCENE = os.path.join(ROOT, "src", "motion_apps", "config", "teach_scene.yaml")


def parse_args(argv):
    parser = argparse.ArgumentParser(prog="record_demo", description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=3, help="teaching sessions recorded (default 3)")
    parser.add_argument("--fps", type=int, default=10, help="frame rate of the episodes and the scene camera")
    parser.add_argument("--output", default=os.path.join(ROOT, "output"), help="folder of runs/ (default output)")
    parser.add_argument("--no-replay", action="store_true", help="skip the replay of episode 0")
    parser.add_argument("--tolerance-mm", type=float, default=2.0, help="replay tool error goal (mm)")
    parser.add_argument("--session-timeout", type=float, default=300.0, help="longest one teaching session (s)")
    args = parser.parse_args(argv)
    if args.episodes < 1:
        parser.error("--episodes must be at least 1")
    return args


def say(text):
    print(f"[record_demo] {text}", flush=True)


def teach_session(run, dataset, index, args):
    """One scripts/teach_sim run recorded as one episode; its teach summary."""
    sessions = os.path.join(run, "sessions")
    log = os.path.join(run, f"teach_session_{index}.log")
    command = [
        os.path.join(ROOT, "scripts", "teach_sim"),
        f"dataset:={dataset}",
        "dataset_start:=true",
        "dataset_gesture:=circle",
        "dataset_camera:=scene",
        f"dataset_fps:={args.fps}",
        f"output_dir:={sessions}",
    ]
    with open(log, "w", encoding="utf-8") as stream:
        done = subprocess.run(command, stdout=stream, stderr=subprocess.STDOUT, timeout=args.session_timeout)
    with open(os.path.join(sessions, "latest", "teach_summary.json"), encoding="utf-8") as stream:
        summary = json.load(stream)
    summary["exit_code"] = done.returncode
    return summary, log


def replay(run, dataset, args):
    """Episode 0 replayed on a fresh simulated arm; the replay report."""
    log = open(os.path.join(run, "replay_sim.log"), "w", encoding="utf-8")  # noqa: SIM115 - open while the sim runs
    sim = subprocess.Popen(
        ["roslaunch", "motion_bringup", "hw_sim.launch", f"scene:={SCENE}"],
        stdout=log,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    report_path = os.path.join(run, "replay.json")
    try:
        done = subprocess.run(
            ["rosrun", "motion_apps", "replay_episode", dataset, "0", "--json", report_path]
            + ["--tolerance-mm", str(args.tolerance_mm)],
            capture_output=True,
            text=True,
            timeout=300,
        )
        say(done.stdout.strip().splitlines()[-1] if done.stdout.strip() else done.stderr.strip()[-300:])
    finally:
        os.killpg(sim.pid, signal.SIGINT)
        try:
            sim.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(sim.pid, signal.SIGKILL)
        log.close()
    if not os.path.exists(report_path):
        return {"episode": 0, "reason": f"replay_episode exited {done.returncode} without a report"}
    with open(report_path, encoding="utf-8") as stream:
        return json.load(stream)


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    run = os.path.join(args.output, "runs", "record_demo-" + datetime.datetime.now().strftime("%Y%m%d-%H%M%S"))
    os.makedirs(run)
    dataset = os.path.join(run, "dataset")
    started = time.monotonic()
    for index in range(args.episodes):
        teach, log = teach_session(run, dataset, index, args)
        records = read_episode_list(dataset)
        if len(records) != index + 1:
            say(f"episode {index}: not saved (see {log})")
            return 1
        success = teach.get("replay_result") == "SUCCESS" and teach["placement_error_mm"] <= teach["tolerance_mm"]
        DatasetStore(dataset).mark(index, success)
        say(
            f"episode {index + 1}/{args.episodes}: {records[-1]['frames']} frames, placement error "
            f"{teach['placement_error_mm']:.2f} mm, success={success} ({time.monotonic() - started:.0f} s)"
        )
    meta, episodes = read_dataset(dataset, video=True)
    records = read_episode_list(dataset)
    if meta["episodes"] != args.episodes or sorted(episodes) != list(range(args.episodes)):
        say(f"LeRobot read {meta['episodes']} episodes back, {args.episodes} were recorded")
        return 1
    say(f"read back by LeRobot {meta['lerobot_version']} ({meta['video_backend']}): {meta['frames']} frames")
    summary = summarize_dataset(dataset, meta, records)
    summary["velocity"] = velocity_agreement(episodes[0], meta["fps"])
    if not args.no_replay:
        summary["replay"] = replay(run, dataset, args)
    plot = plot_episode(
        os.path.join(run, "record_demo.png"), episodes[0], meta["fps"], f"episode 0 of {os.path.basename(run)}"
    )
    summary["plot"] = plot
    summary["seconds"] = round(time.monotonic() - started, 1)
    write_atomic(os.path.join(run, "record_demo.json"), json.dumps(summary, indent=1))
    print(format_summary(summary))
    print(f"results: {run}")
    replay_ok = args.no_replay or summary["replay"].get("tool_error_mm_max") is not None
    return 0 if replay_ok else 1


if __name__ == "__main__":
    sys.exit(main())
