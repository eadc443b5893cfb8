"""Trains the depth tracker's palm correction (motion_sensor.devices.depth_palm_model) and
exports it to ONNX: src/motion_sensor/data/depth_palm.onnx and depth_palm.json.

Data, on the TUNING subjects only of the depth hand bench's split (bench/shrec_hands.py,
``select(data, seed=28, per_subject=2)``; the held-out subjects are never read):
``--per-subject`` SHREC'17 training sequences of each tuning subject (the bench's own two
among them; the default 100 takes 880 of their 1010: all of six subjects' and 100 of each of
the other four's), seeded, rendered by motion_sensor.testing.skeleton_depth with its sensor
noise;
and ``--synthetic`` paths of the parametric hand (motion_sensor.testing.synthetic_depth,
path seeds 101.., none the bench's seed 1), so the network is not fitted to one renderer;
and ``--varied`` more renders of each of those tuning sequences on a varied hand
(motion_sensor.testing.varied_hands: bone lengths, capsule radii, palm slab, thenar and
forearm drawn per sequence, the whole sequence turned so its palm is 0-90 degrees from the
line of sight, rolled and placed at 0.6-1.0 m; seeded, drawn after the rest), so the network
sees more hands than the ten subjects' and tilted palms as often as facing ones.
Each frame is tracked as the tracker runs (reset per sequence), and the crop around its
estimate is kept with the true palm centre (SHREC's joint 1; the synthetic hand's palm
centre). The network: three 3x3 convolution blocks (16, 32, 64 channels, each halving the
crop) and two dense layers to the 3-D offset; MSE, Adam, horizontal flips (x mirrored),
crops shifted and their reference depth moved (see ``batch``), seeded. ``--members``
networks (seeds seed, seed + 1, ..) are exported as one, which averages them on the crop and
its mirror image. Nothing of SHREC'17 is written beside the model beyond the weights.

``--validate-subjects 2,4,..`` trains without those tuning subjects (their varied renders
too) and prints, on their bench sequences, the tracker's per-sequence aligned palm RMS with
and without the correction (how the settings were chosen; also at other weights), and on
all their unvaried and their varied sequences; no model is written then.

Run: nice -n 10 bench/run train_depth_palm [--per-subject 100] [--synthetic 6] [--varied 2]
[--epochs 30] [--cache FILE] [--validate-subjects LIST]. Single-threaded; about 35 min on a
machine shared with one other job: 16 rendering and tracking (59333 frames; 3 min for the
12675 of ``--per-subject 16``), then 6-8 min a network. ``--varied 2`` adds two varied
frames for each unvaried one; ``--cache`` keeps the tracked frames for further runs (a cache
of more varied copies serves a run that asks for fewer).
"""

import argparse
import json
import os
import sys
import time

import numpy as np

import shrec_hands
from bench_common import ROOT

for package in ("motion_sensor", "motion_common"):
    sys.path.insert(0, os.path.join(ROOT, "src", package))

from depth_hand_bench import path_errors  # noqa: E402
from motion_common.atomic_file import write_atomic  # noqa: E402
from motion_sensor.devices.depth_hand import TRACKER_PARAMS, DepthHandTracker  # noqa: E402
from motion_sensor.devices.depth_image import decode_depth, encode_depth_mm  # noqa: E402
from motion_sensor.devices.depth_palm_model import (  # noqa: E402
    CROP_M,
    CROP_PX,
    DEPTH_SCALE_M,
    OFFSET_SCALE_M,
    corrected,
    crop_channels,
    crop_window,
    palm_crop,
)
from motion_sensor.testing.skeleton_depth import PALM, render_skeleton  # noqa: E402
from motion_sensor.testing.synthetic_depth import DEFAULT_INTRINSICS as INTR  # noqa: E402
from motion_sensor.testing.synthetic_depth import hand_path, render_hand  # noqa: E402
from motion_sensor.testing.varied_hands import vary_sequence  # noqa: E402

TRACKER = TRACKER_PARAMS.defaults()
OUT = os.path.join(ROOT, "src", "motion_sensor", "data")
SYNTHETIC_FRAMES = 300
SYNTHETIC_NOISE = 0.0015
# Training crops are this many cells wider on each side than the network's, and shifted by
# up to --shift cells: the estimate the network corrects is off by a few centimetres in any
# direction, and the same frame seen from several shifted crops teaches it that.
MARGIN = 8
CELL_M = CROP_M / CROP_PX


class Recorder:
    """Stands in for the tracker's palm model: keeps the crop around each estimate, corrects
    nothing."""

    def __init__(self):
        self.last = None

    def correct(self, z, top, left, estimate, intr):
        self.last = None
        if palm_crop(z, top, left, estimate, intr) is not None:  # the crops the tracker corrects
            wide = crop_window(z, top, left, estimate, intr, cells=CROP_PX + 2 * MARGIN)
            self.last = (wide, np.array(estimate, float))
        return None


def track_frames(frames, truths, rows, key):
    """Track ``frames`` (depth images, m) of one sequence and append (crop, origin, estimate,
    truth, key) of each frame with a crop to ``rows``."""
    tracker = DepthHandTracker({})
    recorder = Recorder()
    tracker.palm_model = recorder
    for depth, truth in zip(frames, truths):
        recorder.last = None
        tracker.track(depth, INTR)
        if recorder.last is None:
            continue
        (relative, cover, origin), estimate = recorder.last
        rows.append((np.stack((relative, cover)), origin, estimate, np.asarray(truth, float), key))


def roundtrip(depth):
    """What the driver decodes from a 16UC1 image of ``depth`` (m)."""
    return decode_depth("16UC1", INTR.width, INTR.height, INTR.width * 2, encode_depth_mm(depth))


def collect(args):
    """Arrays of every tracked frame: crops, origins, estimates, truths, and per frame the
    sequence number, its subject (0: synthetic) and whether it is a bench sequence."""
    data = shrec_hands.load()
    if data is None:
        sys.exit(f"{shrec_hands.SHREC} not found (../shared absent)")
    tune, _ = shrec_hands.select(data, seed=28, per_subject=2)
    bench = {s.index for s in tune}
    subjects = sorted({s.subject for s in tune})
    rng = np.random.default_rng(args.seed)
    offsets = data["offsets"]
    chosen = []
    for subject in subjects:
        mine = [i for i in np.nonzero(data["subject"] == subject)[0] if i not in bench]
        extra = rng.choice(mine, size=min(len(mine), args.per_subject - 2), replace=False)
        chosen += sorted(i for i in bench if data["subject"][i] == subject) + sorted(int(i) for i in extra)
    rows, meta = [], []
    noise = np.random.default_rng(args.seed + 1)
    start = time.perf_counter()
    for number, index in enumerate(chosen):
        joints = shrec_hands.place(data["joints"][offsets[index] : offsets[index + 1]])
        frames = (roundtrip(render_skeleton(j, INTR, rng=noise)) for j in joints)
        before = len(rows)
        track_frames(frames, joints[:, PALM], rows, number)
        meta += [(number, int(data["subject"][index]), index in bench, 0)] * (len(rows) - before)
        if number % 10 == 9:
            print(f"  {number + 1}/{len(chosen)} sequences, {len(rows)} frames, {time.perf_counter() - start:.0f} s")
    for k in range(args.synthetic):
        poses = hand_path(SYNTHETIC_FRAMES, seed=101 + k)
        frames = (roundtrip(render_hand(p, noise_per_m2=SYNTHETIC_NOISE, rng=noise)) for p in poses)
        before = len(rows)
        track_frames(frames, [p.position for p in poses], rows, len(chosen) + k)
        meta += [(len(chosen) + k, 0, False, 0)] * (len(rows) - before)
    # The same tuning sequences again on varied hands, turned and placed (drawn after the
    # above, from a generator of their own: the unvaried frames are those of --varied 0).
    varied = np.random.default_rng(args.seed + 2)
    number = len(chosen) + args.synthetic
    for copy in range(1, args.varied + 1):
        for index in chosen:
            joints, model = vary_sequence(data["joints"][offsets[index] : offsets[index + 1]], varied)
            frames = (roundtrip(render_skeleton(j, INTR, model, rng=noise)) for j in joints)
            before = len(rows)
            track_frames(frames, joints[:, PALM], rows, number)
            meta += [(number, int(data["subject"][index]), False, copy)] * (len(rows) - before)
            number += 1
        print(f"  varied copy {copy}/{args.varied}: {len(rows)} frames, {time.perf_counter() - start:.0f} s")
    print(f"  {len(rows)} frames in {time.perf_counter() - start:.0f} s")
    meta = np.array(meta)
    return {
        "crop": np.stack([r[0] for r in rows]).astype(np.float16),
        "origin": np.array([r[1] for r in rows]),
        "estimate": np.array([r[2] for r in rows]),
        "truth": np.array([r[3] for r in rows]),
        "sequence": meta[:, 0],
        "subject": meta[:, 1],
        "bench": meta[:, 2].astype(bool),
        "variant": meta[:, 3],
        "sequences": np.array(chosen),
    }


def build_net():
    import torch.nn as nn

    def block(cin, cout):
        return [nn.Conv2d(cin, cout, 3, padding=1), nn.ReLU(), nn.MaxPool2d(2)]

    return nn.Sequential(
        *block(2, 16),
        *block(16, 32),
        *block(32, 64),
        nn.Flatten(),
        nn.Linear(64 * (CROP_PX // 8) ** 2, 64),
        nn.ReLU(),
        nn.Linear(64, 3),
    )


def batch(wide, origin, truth, rng, shift, flip, depth_m):
    """Network inputs and targets (units of OFFSET_SCALE_M) from wide crops (n, 2, cells,
    cells: relative depth, cover): each shifted by up to ``shift`` cells, mirrored with
    probability ``flip``, its reference depth moved by up to ``depth_m``."""
    n = len(wide)
    sx, sy = (rng.integers(-shift, shift + 1, n) if shift else np.zeros(n, int) for _ in range(2))
    dz = rng.uniform(-depth_m, depth_m, n) if depth_m else np.zeros(n)
    out = np.empty((n, 2, CROP_PX, CROP_PX), np.float32)
    target = truth - origin * (1 + dz / origin[:, 2])[:, None]
    for i in range(n):
        r, c = MARGIN + sy[i], MARGIN + sx[i]
        part = wide[i, :, r : r + CROP_PX, c : c + CROP_PX].astype(np.float32)
        out[i] = crop_channels(part[0] - dz[i], part[1])
    target[:, 0] -= sx * CELL_M * (1 + dz / origin[:, 2])
    target[:, 1] -= sy * CELL_M * (1 + dz / origin[:, 2])
    mirror = rng.random(n) < flip if flip else np.zeros(n, bool)
    out[mirror] = out[mirror][..., ::-1]
    target[mirror, 0] *= -1
    return out, target / OFFSET_SCALE_M


def train(wide, origin, truth, args):
    """The trained network (torch) on wide crops, their centre points and the true palm
    centres (see ``batch``)."""
    import torch

    torch.manual_seed(args.seed)
    torch.set_num_threads(1)
    rng = np.random.default_rng(args.seed)
    net = build_net()
    optimiser = torch.optim.Adam(net.parameters(), lr=args.lr, weight_decay=1e-5)
    steps = args.epochs * ((len(wide) + args.batch - 1) // args.batch)
    schedule = torch.optim.lr_scheduler.OneCycleLR(optimiser, max_lr=args.lr, total_steps=steps)
    start = time.perf_counter()
    for epoch in range(args.epochs):
        order = rng.permutation(len(wide))
        total = 0.0
        for b in range(0, len(wide), args.batch):
            pick = order[b : b + args.batch]
            xb, yb = batch(wide[pick], origin[pick], truth[pick], rng, args.shift, 0.5, args.depth_jitter)
            xb, yb = torch.from_numpy(np.ascontiguousarray(xb)), torch.from_numpy(yb.astype(np.float32))
            loss = torch.nn.functional.mse_loss(net(xb), yb)
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            schedule.step()
            total += float(loss.detach()) * len(pick)
        if epoch % 5 == 4 or epoch == args.epochs - 1:
            rms = np.sqrt(total / len(wide) / 3) * OFFSET_SCALE_M * 1000
            took = time.perf_counter() - start
            print(f"  epoch {epoch + 1}/{args.epochs}: training RMS {rms:.2f} mm a coordinate, {took:.0f} s")
    net.eval()
    return net


def averaged(nets):
    """One network of the members' outputs on the crop and on its mirror image (x mirrored
    back), averaged: what is exported."""
    import torch
    import torch.nn as nn

    class Averaged(nn.Module):
        def __init__(self):
            super().__init__()
            self.members = nn.ModuleList(nets)
            self.register_buffer("mirror", torch.tensor([-1.0, 1.0, 1.0]))

        def forward(self, crop):
            flipped = torch.flip(crop, dims=[3])
            outs = [m(crop) for m in self.members] + [m(flipped) * self.mirror for m in self.members]
            return torch.stack(outs).mean(dim=0)

    return Averaged().eval()


def predict(net, crops):
    import torch

    with torch.no_grad():
        return net(torch.from_numpy(crops.astype(np.float32))).numpy().astype(float) * OFFSET_SCALE_M


def aligned_rms_mm(seen, truth, sequence):
    """Per-sequence aligned RMS and p95 (mm), the depth bench's figure (its path_errors)."""
    figures = path_errors(seen, truth, sequence, np.ones(len(seen), bool))["per_sequence_aligned"]
    return figures["rms_mm"], figures["p95_mm"]


def validate(net, frames, left, left_out, args):
    """Prints the left-out subjects' per-sequence aligned RMS / p95 without and with the
    correction: on their bench sequences (what the settings are chosen on; also at other
    weights), on all their unvaried sequences, and on their varied-hand ones."""
    parts = (
        ("their bench sequences", left & frames["bench"]),
        ("all their unvaried sequences", left & (frames["subject"] > 0) & (frames["variant"] == 0)),
        ("their varied-hand sequences", left & (frames["variant"] > 0)),
    )
    for name, rows in parts:
        if not rows.any():
            continue
        crops, _ = batch(frames["crop"][rows], frames["origin"][rows], frames["truth"][rows], None, 0, 0.0, 0.0)
        offset = predict(net, crops)
        seq, truth, estimate = frames["sequence"][rows], frames["truth"][rows], frames["estimate"][rows]
        before = aligned_rms_mm(estimate, truth, seq)
        palm, fell_back = corrected(estimate, frames["origin"][rows], offset, args.max_offset, args.weight)
        after = aligned_rms_mm(palm, truth, seq)
        print(
            f"left-out subjects {left_out}, {name} ({rows.sum()} frames): per-sequence RMS / p95 "
            f"{before[0]:.2f} / {before[1]:.2f} mm without the model, {after[0]:.2f} / {after[1]:.2f} mm with it "
            f"({100 * float(fell_back.mean()):.1f} % of frames fell back)"
        )
        if name == "their bench sequences":
            others = []
            for weight in (0.6, 0.7, 0.8, 0.9, 1.0):
                palm, _ = corrected(estimate, frames["origin"][rows], offset, args.max_offset, weight)
                others.append(f"{weight}: {aligned_rms_mm(palm, truth, seq)[0]:.2f}")
            print(f"  at other weights, RMS mm: {', '.join(others)}")


def export(net, path):
    import torch

    dummy = torch.zeros(1, 2, CROP_PX, CROP_PX)
    torch.onnx.export(
        net,
        dummy,
        path,
        input_names=["crop"],
        output_names=["offset"],
        dynamic_axes={"crop": {0: "n"}, "offset": {0: "n"}},
        opset_version=17,
        dynamo=False,
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--per-subject", type=int, default=100, help="SHREC sequences per tuning subject, at most")
    parser.add_argument("--synthetic", type=int, default=6, help="synthetic hand paths of 300 frames")
    parser.add_argument(
        "--varied", type=int, default=0, help="varied-hand copies of each tuning sequence (testing.varied_hands)"
    )
    parser.add_argument("--epochs", type=int, default=30)
    parser.add_argument("--batch", type=int, default=128)
    parser.add_argument("--lr", type=float, default=3e-3)
    parser.add_argument("--seed", type=int, default=28)
    parser.add_argument("--shift", type=int, default=6, help="crop shifts in training, cells (up to 8)")
    parser.add_argument("--depth-jitter", type=float, default=0.02, help="reference depth moved in training (m)")
    parser.add_argument("--members", type=int, default=2, help="networks averaged (seeds seed, seed + 1, ..)")
    parser.add_argument(
        "--max-offset",
        type=float,
        default=TRACKER["palm_model_max_offset_m"],
        help="the tracker's palm_model_max_offset_m",
    )
    parser.add_argument(
        "--weight", type=float, default=TRACKER["palm_model_weight"], help="the tracker's palm_model_weight"
    )
    parser.add_argument("--cache", help="npz of the tracked frames: read if it exists, else written")
    parser.add_argument("--validate-subjects", help="comma-separated tuning subjects left out and measured")
    parser.add_argument("--out", default=OUT, help="folder of depth_palm.onnx and depth_palm.json")
    args = parser.parse_args()
    # What a cache was collected with: it serves only a run that asks for the same frames
    # (or fewer varied copies).
    collect_args = ("per_subject", "synthetic", "seed", "varied")
    wanted = {name: getattr(args, name) for name in collect_args}
    if args.cache and os.path.exists(args.cache):
        frames = dict(np.load(args.cache))
        cached = dict(zip(collect_args, frames.pop("collected_with", np.full(4, -1)).tolist()))
        if any(cached[name] != wanted[name] for name in collect_args[:3]) or cached["varied"] < args.varied:
            parser.error(
                f"--cache {args.cache} was collected with {cached} (-1: not recorded), this run asks for {wanted}: "
                "delete it or name another"
            )
    else:
        print("rendering and tracking ...", flush=True)
        frames = collect(args)
        if args.cache:
            np.savez(args.cache, collected_with=np.array([wanted[name] for name in collect_args]), **frames)
    # A cache may hold more varied copies than asked for: those are left out.
    keep = frames["variant"] <= args.varied
    frames = {k: (v[keep] if k != "sequences" else v) for k, v in frames.items()}
    count = len(frames["truth"])
    train_rows = np.ones(count, bool)
    if args.validate_subjects:
        left_out = [int(s) for s in args.validate_subjects.split(",")]
        train_rows = ~np.isin(frames["subject"], left_out)
    print(f"training on {train_rows.sum()} frames ...", flush=True)
    members = []
    for k in range(args.members):
        member = argparse.Namespace(**dict(vars(args), seed=args.seed + k))
        members.append(
            train(frames["crop"][train_rows], frames["origin"][train_rows], frames["truth"][train_rows], member)
        )
    net = averaged(members)
    if args.validate_subjects:
        validate(net, frames, ~train_rows, left_out, args)
        return 0
    os.makedirs(args.out, exist_ok=True)
    model = os.path.join(args.out, "depth_palm.onnx")
    export(net, model + ".tmp")
    os.replace(model + ".tmp", model)
    info = {
        "what": "depth tracker palm correction (motion_sensor.devices.depth_palm_model), trained by "
        "bench/train_depth_palm.py",
        "crop": {"side_m": CROP_M, "cells": CROP_PX, "depth_scale_m": DEPTH_SCALE_M, "offset_scale_m": OFFSET_SCALE_M},
        "data": {
            "shrec17_subjects": sorted({int(s) for s in frames["subject"] if s}),
            "shrec17_sequences": [int(i) for i in frames["sequences"]],
            "synthetic_paths": args.synthetic,
            "varied_copies": args.varied,
            "frames": int(count),
        },
        "settings": {
            k: getattr(args, k)
            for k in ("per_subject", "varied", "epochs", "batch", "lr", "seed", "shift", "depth_jitter")
        },
    }
    write_atomic(os.path.join(args.out, "depth_palm.json"), json.dumps(info, indent=2) + "\n")
    print(f"written {model}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
