"""STOP reaction of the hardware layer: from a STOP request (another thread) during a ~3 s
blocking MoveJ to (a) the interrupted move's answer and (b) the arm being still, for the
pybullet driver, the UR driver on its real-time fake controller (ur_rtde_fake) and the
simple_message driver on its byte-level simulated controller over local TCP
(simple_message_fake), through the CommandDispatcher (what motion_controller_server runs),
p50/p99 over N trials.

"Still": sim, every measured joint speed below 0.01 rad/s and staying so (pybullet's
position servo rings down); fake, the fake controller reports no joint moving (the end of
stopJ's deceleration, 2 rad/s^2 by default, from the speed reached when STOP arrived);
simple_message, the simulated controller's arm at rest after STOP_TRAJECTORY (it brakes at
20 rad/s^2, and reports its joints every 10 ms).

Run: bench/run stop_bench [--trials 20]; writes bench/results/stop_bench.json.
"""

import argparse
import os
import sys
import time

import numpy as np

from bench_common import write_results

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "src", "hw_interface"))
sys.path.insert(0, os.path.join(ROOT, "src", "motion_common"))
# The STOP experiment is the rostest check's (tests/nodes/hw_stop_check), in process here.
sys.path.insert(0, os.path.join(ROOT, "tests", "nodes"))
from stop_trial import HOME, LONG, stop_during  # noqa: E402

URDF = os.path.join(ROOT, "src", "motion_common", "urdf", "ur5e.urdf")


def stats(samples):
    ms = np.asarray(samples) * 1e3
    return {
        "p50_ms": round(float(np.percentile(ms, 50)), 2),
        "p99_ms": round(float(np.percentile(ms, 99)), 2),
        "max_ms": round(float(ms.max()), 2),
        "n": int(len(ms)),
    }


def make(name):
    from hw_interface.registry import create_driver

    if name == "pybullet":
        driver = create_driver("pybullet", urdf_path=URDF, initial_joints=list(HOME), real_time=True)

        def still():
            return np.max(np.abs(driver.get_joint_velocities())) < 0.01

    elif name == "simple_message_fake":
        driver = create_driver("simple_message_fake", urdf_path=URDF, initial_joints=list(HOME))

        def still():
            return not driver.fake.is_moving()

    else:
        driver = create_driver("ur_rtde_fake", urdf_path=URDF, initial_joints=list(HOME))

        def still():
            return not driver.fake.is_moving()

    driver.login()
    return driver, still


def trial(dispatcher, driver, still, rng):
    from hw_interface.protocol import CommandIndex, Result

    answer = dispatcher.handle(CommandIndex.MOVE_J, joints=list(HOME))
    assert answer.result == Result.SUCCESS, answer.reason
    # STOP at a random moment 0.3-1.5 s into the move (accelerating or cruising).
    delay = rng.uniform(0.3, 1.5)
    began = time.monotonic()
    runner, stop_at, stop_took = stop_during(
        lambda: dispatcher.handle(CommandIndex.MOVE_J, joints=list(LONG)),
        lambda: time.monotonic() - began >= delay,
        lambda: dispatcher.handle(CommandIndex.STOP),
        timeout=5.0,
    )
    # Still: the first instant from which the arm stays still for 0.1 s.
    still_since = None
    while True:
        now = time.monotonic()
        if still():
            still_since = still_since or now
            if now - still_since >= 0.1:
                break
        else:
            still_since = None
        if now - stop_at > 5.0:
            raise RuntimeError("the arm never came to rest")
        time.sleep(0.001)
    assert runner.error is None and runner.result.result == Result.INTERRUPTED, runner.error or runner.result.reason
    return runner.returned_at - stop_at, stop_took, still_since - stop_at


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trials", type=int, default=20, help="STOPs per driver (default 20)")
    args = parser.parse_args()
    from hw_interface.dispatcher import CommandDispatcher

    rng = np.random.default_rng(7)
    results = {}
    for name in ("pybullet", "ur_rtde_fake", "simple_message_fake"):
        driver, still = make(name)
        dispatcher = CommandDispatcher(driver)
        move_answer, stop_answer, to_still = [], [], []
        print(f"{name}: {args.trials} STOPs during a blocking MoveJ...", flush=True)
        try:
            for _ in range(args.trials):
                a, s, t = trial(dispatcher, driver, still, rng)
                move_answer.append(a)
                stop_answer.append(s)
                to_still.append(t)
        finally:
            driver.disconnect()
            if name == "simple_message_fake":
                driver.fake.close()
        results[name] = {
            "stop_request_to_stop_answer": stats(stop_answer),
            "stop_request_to_interrupted_move_answer": stats(move_answer),
            "stop_request_to_arm_still": stats(to_still),
        }
    results["machine"] = {"cores": os.cpu_count()}
    results["note"] = (
        "in-process through CommandDispatcher; the fake's time to still is stopJ's deceleration "
        "(2 rad/s^2) from the speed at the STOP; simple_message_fake's is the simulated controller's braking "
        "(20 rad/s^2) after STOP_TRAJECTORY over local TCP"
    )
    write_results("stop_bench", results)


if __name__ == "__main__":
    main()
