"""Filter trade-off on the real Leap recordings: jitter against lag.

Jitter: RMS residual (mm) of the filtered palm from its own centred 0.1 s moving average
on the still-hand recordings: the tremor and noise left once slow drift is followed. Lag:
mean distance (mm) between the filtered and the raw palm on the moving recordings. Each
filter family is swept over its smoothing parameters, giving a curve; Leap's own
stabilizedPalmPosition and the paper's mean-10 are single points.

Two named sets of recordings:
- tuning (TUNING_STILL, TUNING_MOVING, all in tests/data): the sweeps run there and the
  shipped defaults were chosen there;
- evaluation (EVALUATION_STILL, EVALUATION_MOVING: recordings the tuning never saw, from
  ../shared/data/leap_v6, falling back to tests/data for those it has): the shipped
  defaults are then measured there, against mean-10 on the same recordings.
Their time lag is also measured on slow moves (a still-hand recording plus a ramp), where a
speed-adaptive filter smooths most.

What the evaluation set allows (``limits``):
- a centred (non-causal, so not for live use) Gaussian smoother at mean-10's jitter: the
  lag left is mostly the noise it removes, a reference for fixed smoothers (an adaptive
  filter can do better: the default one_euro does on the tuning set);
- the default one_euro's lag split by the hand's net speed over 0.2 s, next to the speeds a
  still recording's palm moves at: a speed gate can only cut the lag of moves faster than
  the still hands it must hold steady;
- every swept setting measured on the evaluation set too (never chosen there): the least
  evaluation lag of those at least as steady as mean-10 there, and the steadiest of those
  with a third of its lag.

Run: bench/run filter_bench
Writes bench/results/filter_bench.json and bench/results/filter_tradeoff.png.
"""

import functools
import json
import os
import sys

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "src", "motion_sensor"))

from bench_common import RESULTS, write_results  # noqa: E402
from motion_sensor.devices.leap_v6 import read_recording, select_primary  # noqa: E402
from motion_sensor.sequencing.filters import FILTER_PARAMS, make_filter  # noqa: E402

TUNING_STILL = ["Waiting-110fps", "waiting-short"]
TUNING_MOVING = ["wave", "flapping", "test-paddle-rightwards", "rollAndPitchCropped"]
EVALUATION_STILL = ["HandSplay-110fps"]
EVALUATION_MOVING = ["brian", "grab", "gun", "three-claps", "rollAndPitchWithEntry", "confidence-demo", "pinch"]
SHARED = os.path.join(ROOT, "..", "shared", "data", "leap_v6")
SLOW_SPEEDS = (0.02, 0.05, 0.1, 0.2, 0.5)  # m/s, ramps added to a still-hand recording
DRIFT_WINDOWS = (0.3, 0.4, 0.5, 0.6, 0.7)  # s, one_euro's drift_window swept
# Curve name -> (filter name, parameter sets). "one_euro" and "kalman" are the shipped
# filters; "one_euro_classic" and "kalman_cv" are the textbook versions they extend.
SWEEPS = {
    "mean": ("mean", [{"queue_size": n} for n in (2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 30)]),
    "one_euro_classic": (
        "one_euro",
        [
            {"mincutoff": m, "beta": b, "dcutoff": d, "speed_threshold": 0.0, "speed_window": 0.0, "drift_window": 0.0}
            for m in (0.3, 1.0, 3.0)
            for b in (10.0, 20.0, 40.0, 80.0, 160.0, 320.0)
            for d in (0.3, 1.0, 3.0)
        ],
    ),
    "one_euro": (
        "one_euro",
        [
            {"mincutoff": m, "beta": b, "dcutoff": d, "speed_threshold": v, "speed_window": 0.0, "drift_window": 0.0}
            for m in (0.3, 0.5, 1.0, 2.0, 3.0, 5.0)
            for b in (320.0, 640.0, 1280.0)
            for d in (1.0, 2.0, 4.0)
            for v in (0.05, 0.08, 0.1, 0.15, 0.2)
        ],
    ),
    "one_euro+deadband": (
        "one_euro",
        [
            {"mincutoff": m, "deadband": db, "speed_window": 0.0, "drift_window": 0.0}
            for m in (1.0, 3.0)
            for db in (0.0002, 0.0005, 0.001, 0.002)
        ],
    ),
    # Speed as the net move over 0.2 s (the shipped one_euro without its drift gate).
    "one_euro_window": (
        "one_euro",
        [
            {
                "mincutoff": m,
                "beta": b,
                "speed_threshold": v,
                "speed_window": 0.2,
                "lag_compensation": c,
                "drift_window": 0.0,
            }
            for m in (2.0, 3.0, 4.0)
            for b in (640.0, 1280.0)
            for v in (0.06, 0.08, 0.1)
            for c in (0.0, 0.3)
        ],
    ),
    # The shipped one_euro plus the drift gate: a slow move's net speed over a longer window.
    "one_euro_drift": (
        "one_euro",
        [
            {"drift_window": w, "drift_threshold": v}
            for w in DRIFT_WINDOWS
            for v in (0.035, 0.04, 0.045, 0.05, 0.055, 0.06, 0.065, 0.07)
        ],
    ),
    "kalman_cv": (
        "kalman",
        [
            {"process_noise": q, "measurement_noise": r, "maneuver_process_noise": 0.0}
            for r in (0.0003, 0.001)
            for q in (1e-5, 3e-5, 1e-4, 3e-4, 1e-3, 3e-3, 0.01, 0.03, 0.1, 0.3, 1.0)
        ],
    ),
    "kalman": (
        "kalman",
        [
            {"process_noise": 1e-5, "measurement_noise": r, "maneuver_process_noise": qm, "switch_probability": p}
            for r in (0.003, 0.005, 0.01)
            for qm in (3.0, 10.0, 30.0, 100.0)
            for p in (0.005, 0.05)
        ],
    ),
}


def load(name):
    """(stamps s, raw positions m, Leap-stabilised positions m, quaternions) of the primary hand."""
    for folder in (SHARED, os.path.join(ROOT, "tests", "data")):
        path = os.path.join(folder, f"{name}.jsonl.gz")
        if os.path.exists(path):
            break
    else:
        return None
    recording = read_recording(path)
    rows = [(f.timestamp, select_primary(f)) for f in recording.frames if f.hands]
    stamps = np.array([t for t, _ in rows])
    raw = np.array([h.position for _, h in rows])
    stabilized = np.array([h.stabilized_position for _, h in rows])
    quats = np.array([h.orientation for _, h in rows])
    return stamps, raw, stabilized, quats


def run_filter(name, params, stamps, raw, quats):
    """Filtered positions of one recording."""
    f = make_filter(name, **params)
    return np.array([f.update(t, p, q)[0] for t, p, q in zip(stamps, raw, quats)])


def jitter_mm(stamps, positions, skip=10):
    """RMS residual (mm, 3D) from the centred 0.1 s moving average of the signal itself.

    A hand held "still" drifts slowly; the 0.1 s trend follows that drift, and what is
    left is tremor and sensor noise (the raw palm shows 0.2-0.4 mm per axis, as the
    recordings' README reports).
    """
    rate = 1.0 / np.median(np.diff(stamps))
    half = max(1, int(round(0.05 * rate)))
    kernel = np.ones(2 * half + 1) / (2 * half + 1)
    trend = np.column_stack([np.convolve(positions[:, i], kernel, mode="same") for i in range(3)])
    residual = (positions - trend)[max(skip, half) : -half]
    return float(np.sqrt(np.mean(np.sum(residual**2, axis=1)))) * 1000


def lag_mm(raw, filtered, skip=10):
    """Mean distance between filtered and raw positions (mm), after a warm-up."""
    return float(np.mean(np.linalg.norm(filtered[skip:] - raw[skip:], axis=1))) * 1000


def evaluate(data, produce, still=TUNING_STILL, moving=TUNING_MOVING):
    """(jitter, lag) averaged over the still and the moving recordings."""
    jitter = np.mean([jitter_mm(data[n][0], produce(n)) for n in still])
    lag = np.mean([lag_mm(data[n][1], produce(n)) for n in moving])
    return float(jitter), float(lag)


def _swept(data, filter_name, params, recording):
    """Filtered positions of a recording with one swept parameter set."""
    stamps, raw, _, quats = data[recording]
    return run_filter(filter_name, params, stamps, raw, quats)


def run_default(data, filter_name, recording):
    """Filtered positions of a recording with the filter's shipped defaults."""
    stamps, raw, _, quats = data[recording]
    return run_filter(filter_name, {}, stamps, raw, quats)


def slow_time_lag_ms(data, filter_name):
    """Time lag (ms) of a filter with its shipped defaults on slow moves: the still-hand
    recording plus a ramp at each speed.

    The distance behind along the ramp, divided by its speed, over the last half of the
    recording (the tremor averages out). A speed-adaptive filter smooths most here.
    """
    stamps, raw, _, quats = data["Waiting-110fps"]
    lags = {}
    half = len(stamps) // 2
    for speed in SLOW_SPEEDS:
        moved = raw + np.outer(speed * (stamps - stamps[0]), [1.0, 0.0, 0.0])
        filtered = run_filter(filter_name, {}, stamps, moved, quats)
        lags[str(speed)] = round(float(np.mean(moved[half:, 0] - filtered[half:, 0]) / speed * 1000), 1)
    return lags


def pareto(curve):
    """The configurations no other beats on both jitter and lag, by rising jitter."""
    points = sorted(curve, key=lambda c: (c["jitter_mm"], c["lag_mm"]))
    front, best_lag = [], float("inf")
    for point in points:
        if point["lag_mm"] < best_lag:
            front.append(point)
            best_lag = point["lag_mm"]
    return front


def lag_at_jitter(curve, jitter):
    """Lag a swept filter has at a given jitter (linear interpolation on its Pareto front)."""
    points = pareto(curve)
    xs, ys = [c["jitter_mm"] for c in points], [c["lag_mm"] for c in points]
    if not xs[0] <= jitter <= xs[-1]:
        return None
    return float(np.interp(jitter, xs, ys))


def main():
    data = {n: load(n) for n in TUNING_STILL + TUNING_MOVING + EVALUATION_STILL + EVALUATION_MOVING}
    missing = sorted(n for n, d in data.items() if d is None)
    if any(n in missing for n in TUNING_STILL + TUNING_MOVING):
        raise SystemExit(f"filter_bench: tuning recordings missing: {missing}")
    data = {n: d for n, d in data.items() if d is not None}
    results = {
        "raw": dict(zip(("jitter_mm", "lag_mm"), evaluate(data, lambda n: data[n][1]))),
        "leap_stabilized": dict(zip(("jitter_mm", "lag_mm"), evaluate(data, lambda n: data[n][2]))),
    }
    curves = {}
    total = sum(len(sweep) for _, sweep in SWEEPS.values())
    done = 0
    held_out = evaluation_split(data)
    for curve, (name, sweep) in SWEEPS.items():
        curves[curve] = []
        for params in sweep:
            produce = functools.partial(_swept, data, name, params)
            jitter, lag = evaluate(data, produce)
            point = {"params": params, "jitter_mm": round(jitter, 4), "lag_mm": round(lag, 3)}
            if all(held_out):
                # Measured, never chosen on: what the evaluation set allows (see limits).
                held_jitter, held_lag = evaluate(data, produce, *held_out)
                point.update(evaluation_jitter_mm=round(held_jitter, 4), evaluation_lag_mm=round(held_lag, 3))
            curves[curve].append(point)
            done += 1
            print(f"[{done:3d}/{total}] {curve:17s} {params}: jitter {jitter:.4f} mm, lag {lag:.2f} mm", flush=True)
    mean10 = next(c for c in curves["mean"] if c["params"]["queue_size"] == 10)
    results["mean10"] = mean10
    verdict = {}
    for curve in (
        "one_euro_classic",
        "one_euro",
        "one_euro+deadband",
        "one_euro_window",
        "one_euro_drift",
        "kalman_cv",
        "kalman",
    ):
        at_mean10 = lag_at_jitter(curves[curve], mean10["jitter_mm"])
        at_leap = lag_at_jitter(curves[curve], results["leap_stabilized"]["jitter_mm"])
        verdict[curve] = {
            "pareto": pareto(curves[curve]),
            "lag_at_mean10_jitter_mm": at_mean10,
            "ratio_to_mean10_lag": None if at_mean10 is None else round(at_mean10 / mean10["lag_mm"], 3),
            "meets_one_third_goal": None if at_mean10 is None else at_mean10 <= mean10["lag_mm"] / 3,
            "lag_at_leap_jitter_mm": at_leap,
            "beats_leap_stabilizer": None if at_leap is None else at_leap < results["leap_stabilized"]["lag_mm"],
        }
    results["curves"] = curves
    results["verdict"] = verdict
    results["drift_choice"] = choose_drift(data, curves["one_euro_drift"])
    results["shipped_defaults"] = check_defaults(data)
    results["shipped_defaults"]["evaluation_missing"] = missing
    results["limits"] = limits(data, results["shipped_defaults"])
    results["limits"]["evaluation_sweeps"] = evaluation_sweeps(curves, results["shipped_defaults"])
    write_results("filter_bench", results, show=False)
    plot(results, os.path.join(RESULTS, "filter_tradeoff.png"))
    summary = {name: {k: v for k, v in verdict.items() if k != "pareto"} for name, verdict in verdict.items()}
    print(
        json.dumps(
            {
                "raw": results["raw"],
                "leap_stabilized": results["leap_stabilized"],
                "mean10": results["mean10"],
                "verdict": summary,
                "shipped_defaults": results["shipped_defaults"],
                "limits": results["limits"],
            },
            indent=2,
        )
    )
    print(f"plot: {os.path.join(RESULTS, 'filter_tradeoff.png')}")


def check_defaults(data):
    """The shipped defaults (mean-10, one_euro, kalman) on the tuning and the evaluation
    recordings, and their time lag on slow moves."""
    still, moving = evaluation_split(data)
    out = {
        "tuning_recordings": {"still": TUNING_STILL, "moving": TUNING_MOVING},
        "evaluation_recordings": {"still": still, "moving": moving},
    }
    rows = {"raw": lambda n: data[n][1], "leap_stabilized": lambda n: data[n][2]}
    for name in ("mean", "one_euro", "kalman"):
        rows[name] = functools.partial(run_default, data, name)
    for label, produce in rows.items():
        tuned = evaluate(data, produce)
        evaluated = evaluate(data, produce, still, moving)
        out[label] = {
            "tuning_jitter_mm": round(tuned[0], 4),
            "tuning_lag_mm": round(tuned[1], 3),
            "evaluation_jitter_mm": round(evaluated[0], 4),
            "evaluation_lag_mm": round(evaluated[1], 3),
        }
        if label in ("mean", "one_euro", "kalman"):
            out[label]["slow_move_time_lag_ms"] = slow_time_lag_ms(data, label)
    for label in ("one_euro", "kalman"):
        for split in ("tuning", "evaluation"):
            out[label][f"{split}_lag_ratio_to_mean10"] = round(
                out[label][f"{split}_lag_mm"] / out["mean"][f"{split}_lag_mm"], 3
            )
            out[label][f"{split}_steadier_than_mean10"] = (
                out[label][f"{split}_jitter_mm"] <= out["mean"][f"{split}_jitter_mm"]
            )
        out[label]["meets_one_third_on_evaluation"] = bool(
            out[label]["evaluation_steadier_than_mean10"] and out[label]["evaluation_lag_ratio_to_mean10"] <= 1 / 3
        )
    return out


def trailing_net_speeds(stamps, positions, window):
    """Net displacement over the last ``window`` s divided by its time (m/s), as one_euro's
    drift gate measures it: only at frames with a whole window of history."""
    start = np.searchsorted(stamps, stamps - window, side="right") - 1
    whole = start >= 0
    start = np.maximum(start, 0)
    span = np.maximum(stamps - stamps[start], 1e-9)
    return (np.linalg.norm(positions - positions[start], axis=1) / span)[whole]


def choose_drift(data, curve):
    """one_euro's drift gate as chosen on the tuning recordings: among the swept settings
    whose threshold lies above the largest net speed the tuning still hands reach over its
    window (the gate never opens on them, so they are filtered as without it), the least
    tuning lag. The evaluation set is never looked at."""
    reach = {
        str(w): round(max(float(trailing_net_speeds(data[n][0], data[n][1], w).max()) for n in TUNING_STILL), 4)
        for w in DRIFT_WINDOWS
    }
    shut = [p for p in curve if p["params"]["drift_threshold"] > reach[str(p["params"]["drift_window"])]]
    if not shut:
        raise SystemExit(f"filter_bench: no swept drift threshold lies above the still hands' net speeds {reach}")
    chosen = min(shut, key=lambda p: p["lag_mm"])
    schema = FILTER_PARAMS.params["one_euro"].schema.defaults()
    shipped = {k: schema[k] for k in ("drift_window", "drift_threshold")}
    return {
        "rule": "least tuning lag among thresholds above the tuning still hands' largest net speed over the window",
        "still_hands_largest_net_speed_m_s": reach,
        "chosen": chosen,
        "shipped": shipped,
        "shipped_is_chosen": shipped == chosen["params"],
    }


def net_speeds(stamps, positions, window=0.2):
    """Net displacement over a centred ``window`` divided by its time (m/s), per frame."""
    start = np.searchsorted(stamps, stamps - window / 2)
    end = np.searchsorted(stamps, stamps + window / 2, side="right") - 1
    span = np.maximum(stamps[end] - stamps[start], 1e-9)
    return np.linalg.norm(positions[end] - positions[start], axis=1) / span


def centred_floor(data, still, moving, jitter_goal):
    """Lag of a centred Gaussian smoother whose jitter equals ``jitter_goal`` (interpolated
    over its width): what a fixed smoother that could see the future would keep."""
    from scipy.ndimage import gaussian_filter1d

    points = []
    for sigma in np.arange(1.0, 6.01, 0.25):  # frames
        smooth = functools.partial(gaussian_filter1d, sigma=sigma, axis=0, mode="nearest")
        points.append(evaluate(data, lambda n, smooth=smooth: smooth(data[n][1]), still, moving))
    jitters, lags = zip(*sorted(points))
    if not jitters[0] <= jitter_goal <= jitters[-1]:
        raise ValueError(f"jitter {jitter_goal:.3f} mm outside the widths' {jitters[0]:.3f}-{jitters[-1]:.3f} mm")
    return float(np.interp(jitter_goal, jitters, lags))


def evaluation_sweeps(curves, defaults):
    """Over every swept setting measured on the evaluation set: the least evaluation lag
    among those no noisier there than mean-10 (and its ratio to mean-10's evaluation lag),
    and the least evaluation jitter among those with at most a third of that lag."""
    mean = defaults["mean"]
    points = [p for curve in curves.values() for p in curve if "evaluation_lag_mm" in p]
    if not points:
        return None
    steady = [p for p in points if p["evaluation_jitter_mm"] <= mean["evaluation_jitter_mm"]]
    quick = [p for p in points if p["evaluation_lag_mm"] <= mean["evaluation_lag_mm"] / 3]
    best = min(steady, key=lambda p: p["evaluation_lag_mm"]) if steady else None
    steadiest = min(quick, key=lambda p: p["evaluation_jitter_mm"]) if quick else None
    return {
        "settings": len(points),
        "least_lag_as_steady_as_mean10": best,
        "least_lag_ratio_to_mean10": round(best["evaluation_lag_mm"] / mean["evaluation_lag_mm"], 3) if best else None,
        "steadiest_with_a_third_of_the_lag": steadiest,
        "mean10_evaluation_jitter_mm": mean["evaluation_jitter_mm"],
    }


def evaluation_split(data):
    """(still, moving) evaluation recordings that were found."""
    return [n for n in EVALUATION_STILL if n in data], [n for n in EVALUATION_MOVING if n in data]


def limits(data, defaults, speed_bins=(0.0, 0.02, 0.05, 0.08, 0.12, 0.2, 0.5, np.inf), skip=10):
    """What the evaluation set allows: the centred smoother's ratio to mean-10's lag on each
    split (mean-10's figures from ``defaults``, check_defaults' result), and where the
    default one_euro's evaluation lag lies by the hand's net speed."""
    splits = {"tuning": (TUNING_STILL, TUNING_MOVING), "evaluation": evaluation_split(data)}
    out = {"speed_bins_m_s": [float(b) for b in speed_bins[:-1]]}
    for split, (still, moving) in splits.items():
        mean = defaults["mean"]
        floor = centred_floor(data, still, moving, mean[f"{split}_jitter_mm"])
        out[f"{split}_centred_floor_lag_mm"] = round(floor, 3)
        out[f"{split}_centred_floor_ratio_to_mean10"] = round(floor / mean[f"{split}_lag_mm"], 3)
    still, moving = splits["evaluation"]
    share = np.zeros(len(speed_bins) - 1)
    for name in moving:
        stamps, raw = data[name][0], data[name][1]
        distance = np.linalg.norm(run_default(data, "one_euro", name) - raw, axis=1)[skip:]
        bins = np.digitize(net_speeds(stamps, raw)[skip:], speed_bins) - 1
        share += np.bincount(bins, weights=distance, minlength=len(share))[: len(share)] / len(distance) * 1000
    share /= len(moving)
    out["evaluation_one_euro_lag_mm_by_speed"] = [round(float(v), 3) for v in share]
    frames = np.concatenate([net_speeds(data[n][0], data[n][1])[skip:] for n in still])
    counts = np.bincount(np.digitize(frames, speed_bins) - 1, minlength=len(share))[: len(share)]
    out["evaluation_still_frames_by_speed"] = [round(float(v), 3) for v in counts / len(frames)]
    return out


def plot(results, path):
    """Jitter-lag trade-off curves, and the shipped defaults' time lag on slow moves."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax_slow) = plt.subplots(1, 2, figsize=(13, 5.5), gridspec_kw={"width_ratios": [3, 2]})
    # One colour per family in both panels; dashed = the textbook version.
    styles = {
        "mean": ("o-", "tab:blue"),
        "one_euro_classic": ("s--", "tab:orange"),
        "one_euro": ("s-", "tab:orange"),
        "one_euro+deadband": ("D:", "tab:red"),
        "one_euro_window": ("v-", "tab:purple"),
        "one_euro_drift": ("P-", "tab:brown"),
        "kalman_cv": ("^--", "tab:green"),
        "kalman": ("^-", "tab:green"),
    }
    for name, curve in results["curves"].items():
        front = pareto(curve)
        ax.plot(
            [c["jitter_mm"] for c in front],
            [c["lag_mm"] for c in front],
            styles[name][0],
            color=styles[name][1],
            label=f"{name} (best settings of the sweep)",
            ms=4,
        )
    ax.plot(results["raw"]["jitter_mm"], 0.01, "kx", ms=9, label="raw palm (lag 0, drawn at 0.01)")
    ax.plot(
        results["leap_stabilized"]["jitter_mm"],
        results["leap_stabilized"]["lag_mm"],
        "r*",
        ms=13,
        label="Leap stabilizedPalmPosition",
    )
    ax.plot(
        results["mean10"]["jitter_mm"],
        results["mean10"]["lag_mm"],
        "o",
        mfc="none",
        mec="k",
        ms=12,
        label="mean, queue 10 (paper)",
    )
    goal = results["mean10"]["lag_mm"] / 3
    ax.plot([results["mean10"]["jitter_mm"]] * 2, [goal, results["mean10"]["lag_mm"]], "k:", lw=1)
    ax.plot(results["mean10"]["jitter_mm"], goal, "k_", ms=14, label="goal: 1/3 of mean-10's lag")
    ax.set_xlabel("jitter on still hands: RMS residual [mm]  (lower is steadier)")
    ax.set_ylabel("lag on moving hands: mean distance behind raw [mm]")
    ax.set_yscale("log")
    ax.set_xscale("log")
    ax.set_title("Trade-off on real Leap recordings (down-left is better)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    defaults = results["shipped_defaults"]
    for name in ("mean", "one_euro", "kalman"):
        lags = defaults[name]["slow_move_time_lag_ms"]
        ax_slow.plot(
            [float(v) for v in lags],
            list(lags.values()),
            styles[name][0],
            color=styles[name][1],
            label=f"{name} (shipped defaults)",
        )
    ax_slow.set_xscale("log")
    ax_slow.set_xticks(SLOW_SPEEDS)
    ax_slow.set_xticklabels([f"{v:g}" for v in SLOW_SPEEDS])
    ax_slow.minorticks_off()
    ax_slow.set_xlabel("hand speed [m/s] (ramp added to a still-hand recording)")
    ax_slow.set_ylabel("time lag [ms]")
    ax_slow.set_title("Time lag on slow moves")
    ax_slow.grid(alpha=0.3, which="both")
    ax_slow.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
