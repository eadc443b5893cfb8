"""Training of the skeleton gesture network (torch, CPU), its user-independent estimate
and its ONNX export. Development only: torch comes from requirements-train.txt; the
runtime reads the exported model with onnxruntime (``skeleton_classifier``).

Reproducible: numpy and torch are seeded from ``TrainConfig.seed`` and torch runs
deterministic kernels on ``threads`` threads (1 by default: the machine is shared).

Sequences are turned into the network's input frame (``skeleton_features.to_model_frame``)
before anything else. Augmentation, drawn per sequence and epoch: a rotation (up to ``rotate_deg`` about the
vertical axis, a third of it about the two others), a scale, Gaussian joint noise and a
time warp (a random crop of up to ``crop`` of the sequence at each end and a smooth
non-uniform speed), and with probability ``lead_in`` a way in: the hand rests for up to
0.3 s 2-15 cm away and moves smoothly (0.2-0.6 s) to where the gesture starts, as in the
windows the online spotter classifies.

Rejection (outlier exposure): with a ``NegativeSource`` (``skeleton_negatives``: real Leap
motion, transitions between gestures), each epoch adds ``reject_share`` x the training
set's size of its windows, whose target is the uniform distribution over the classes
(weight ``reject_weight``): the network learns to be unsure on motion that is no gesture.

Spotted windows (``spot_share`` > 0): windows cut from continuous streams of the training
subjects by the spotter's own segmentation (``skeleton_spotted_windows``, window starts
``SPOT_WINDOW_STARTS``), labelled with the gesture they cover; each epoch adds
``spot_share`` x the training set's size of them (augmented like the sequences, without a
way in: they hold one), the few that cover too little of a gesture as windows to reject.
``pair_weight`` weighs the loss of the classes the teach commands are confused with and
those commands (``CONFUSED_CLASSES``) that much more.
"""

import os
import time
import warnings
from dataclasses import asdict, dataclass

import numpy as np

from motion_sensor.gestures.skeleton_features import FRAMES, batch_features, skeleton_features, to_model_frame

__all__ = [
    "CONFUSED_CLASSES",
    "SPOT_WINDOW_STARTS",
    "TrainConfig",
    "augment",
    "train_model",
    "predict",
    "export_onnx",
    "fold_28_to_14",
]

# The pairs held-out subjects' non-command gestures are read as teach commands by every
# seed: swipe down as tap, swipe X as swipe left, pinch as grab.
CONFUSED_CLASSES = ("swipe_down", "tap", "swipe_x", "swipe_left", "pinch", "grab")
# Where the spotted training windows start (fractions of the segment): the spotter's two
# and the starts between and after them, for partial windows.
SPOT_WINDOW_STARTS = [0.0, 0.1, 0.2, 0.3]


@dataclass
class TrainConfig:
    """Training settings; the defaults trained the shipped model."""

    filters: int = 32
    epochs: int = 100
    batch: int = 64
    lr: float = 2e-3
    weight_decay: float = 1e-4
    label_smoothing: float = 0.1
    rotate_deg: float = 15.0
    scale: float = 0.15
    noise_m: float = 0.002
    crop: float = 0.1
    warp: float = 0.3
    lead_in: float = 0.0
    reject_share: float = 0.0
    reject_weight: float = 1.0
    spot_share: float = 0.0
    pair_weight: float = 1.0
    seed: int = 0
    threads: int = 1

    def as_dict(self):
        return asdict(self)


def _rotation(rng, max_deg):
    angles = np.radians(rng.uniform(-1.0, 1.0, 3) * np.array([max_deg / 3, max_deg / 3, max_deg]))
    cx, cy, cz = np.cos(angles)
    sx, sy, sz = np.sin(angles)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def augment(sequence, rng, config, way_in=True):
    """One augmented copy of ``sequence`` (L, 22, 3) and the fractional frames to sample
    (``way_in``: the sequence may get one, with probability ``config.lead_in``)."""
    seq = np.asarray(sequence, dtype=np.float64)
    centre = seq[:, 1].mean(axis=0)
    seq = (seq - centre) @ _rotation(rng, config.rotate_deg).T
    seq = seq * (1.0 + rng.uniform(-config.scale, config.scale)) + centre
    seq = seq + rng.normal(0.0, config.noise_m, seq.shape)
    if way_in and config.lead_in and rng.uniform() < config.lead_in:
        seq = np.concatenate([_way_in(seq, rng), seq])
    last = len(seq) - 1
    start = rng.uniform(0.0, config.crop) * last
    end = last - rng.uniform(0.0, config.crop) * last
    u = np.linspace(0.0, 1.0, FRAMES)
    bend = rng.uniform(-config.warp, config.warp)
    warped = u + bend * u * (1.0 - u)  # monotonic while |bend| < 1
    return seq, start + warped * (end - start)


def _way_in(seq, rng, rate=30.0):
    """Frames before ``seq``: a rest 2-15 cm away, then a smooth move to its first pose."""
    direction = rng.normal(size=3)
    origin = seq[0 if rng.uniform() < 0.5 else -1] + direction / np.linalg.norm(direction) * rng.uniform(0.02, 0.15)
    rest = np.repeat(origin[None], int(rng.uniform(0.0, 0.3) * rate), axis=0)
    steps = max(2, int(rng.uniform(0.2, 0.6) * rate))
    ease = 0.5 - 0.5 * np.cos(np.pi * np.arange(steps) / steps)
    move = origin + (seq[0] - origin) * ease[:, None, None]
    return np.concatenate([rest, move]) if len(rest) else move


def _torch(config):
    import torch

    torch.manual_seed(config.seed)
    torch.set_num_threads(config.threads)
    torch.use_deterministic_algorithms(True)
    return torch


def train_model(dataset, config=None, log=None, negatives=None):
    """Train a ``SkeletonNet`` on ``dataset`` (a ``SkeletonDataset``), rejecting the windows
    of ``negatives`` (a ``NegativeSource``, optional); returns it in eval mode."""
    from motion_sensor.gestures.skeleton_network import SkeletonNet

    config = config or TrainConfig()
    torch = _torch(config)
    rng = np.random.default_rng(config.seed)
    model = SkeletonNet(filters=config.filters)
    optimizer = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    n_neg = int(round(config.reject_share * len(dataset))) if negatives else 0
    pool = _spotted_pool(dataset, config)
    n_spot = int(round(config.spot_share * len(dataset))) if pool is not None else 0
    steps_per_epoch = max(1, int(np.ceil((len(dataset) + n_spot + n_neg) / config.batch)))
    scheduler = torch.optim.lr_scheduler.OneCycleLR(
        optimizer, max_lr=config.lr, total_steps=config.epochs * steps_per_epoch, pct_start=0.1
    )
    loss14, loss28 = _losses(torch, config)
    started = time.monotonic()
    inputs = [to_model_frame(s) for s in dataset.sequences]
    for epoch in range(config.epochs):
        model.train()
        spot = rng.integers(len(pool[0]), size=n_spot) if n_spot else np.zeros(0, dtype=int)
        drawn = [to_model_frame(s) for s in negatives.draw(rng, n_neg)] if n_neg else []
        augmented = [augment(s, rng, config) for s in inputs]
        augmented += [augment(pool[0][k], rng, config, way_in=False) for k in spot]
        augmented += [augment(s, rng, config) for s in drawn]
        sequences, positions = zip(*augmented, strict=True)
        jcd, slow, fast = (torch.as_tensor(a) for a in batch_features(sequences, positions))
        none = np.full(n_neg, -1)  # a window to reject
        y14 = torch.as_tensor(np.concatenate([dataset.label14, pool[1][spot] if n_spot else [], none]).astype(np.int64))
        y28 = torch.as_tensor(np.concatenate([dataset.label28, pool[2][spot] if n_spot else [], none]).astype(np.int64))
        order = torch.as_tensor(rng.permutation(len(augmented)))
        total = 0.0
        for first in range(0, len(order), config.batch):
            idx = order[first : first + config.batch]
            if len(idx) < 2:  # batch norm needs two samples
                continue
            out14, out28 = model(jcd[idx], slow[idx], fast[idx])
            pos = y14[idx] >= 0
            neg = ~pos
            loss = 0.0
            if pos.any():
                loss = loss14(out14[pos], y14[idx[pos]]) + loss28(out28[pos], y28[idx[pos]])
            if neg.any():  # cross-entropy against the uniform distribution
                uniform = -out14[neg].log_softmax(1).mean(1) - out28[neg].log_softmax(1).mean(1)
                loss = loss + config.reject_weight * uniform.sum() / len(idx)
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            scheduler.step()
            total += loss.item() * len(idx)
        if log and (epoch + 1) % max(1, config.epochs // 8) == 0:
            log(
                f"epoch {epoch + 1}/{config.epochs}: loss {total / len(dataset):.3f} "
                f"({time.monotonic() - started:.0f} s)"
            )
    model.eval()
    return model


def _spotted_pool(dataset, config):
    """(windows in the model frame, label14, label28) of the spotted windows, or None."""
    if config.spot_share <= 0.0:
        return None
    from motion_sensor.gestures.skeleton_spotted_windows import spotted_windows

    found = spotted_windows(
        dataset, np.random.default_rng(config.seed + 1), params={"window_starts": SPOT_WINDOW_STARTS}
    )
    if not len(found):
        return None
    return [to_model_frame(w) for w in found.windows], found.label14, found.label28


def _losses(torch, config):
    """The 14- and 28-class losses; with ``pair_weight`` the ``CONFUSED_CLASSES`` weigh more."""
    from motion_sensor.gestures.skeleton_dataset import CLASSES_14

    if config.pair_weight == 1.0:
        plain = torch.nn.CrossEntropyLoss(label_smoothing=config.label_smoothing)
        return plain, plain
    w14 = np.array([config.pair_weight if c in CONFUSED_CLASSES else 1.0 for c in CLASSES_14], dtype=np.float32)
    w28 = np.repeat(w14, 2)  # gesture x (one finger, whole hand)
    return tuple(
        torch.nn.CrossEntropyLoss(weight=torch.as_tensor(w), label_smoothing=config.label_smoothing) for w in (w14, w28)
    )


def fold_28_to_14(prob28):
    """28-class probabilities (gesture x finger) summed to the 14 gestures."""
    prob28 = np.asarray(prob28)
    return prob28.reshape(len(prob28), 14, 2).sum(axis=2)


def predict(model, sequences):
    """(prob14, prob28) of a trained model on sequences; prob14 averages the 14-class head
    with the 28-class head folded onto the gestures (what ``skeleton_classifier`` does)."""
    import torch

    jcd, slow, fast = (torch.as_tensor(a) for a in batch_features([to_model_frame(s) for s in sequences]))
    with torch.no_grad():
        out14, out28 = model(jcd, slow, fast)
    prob14 = torch.softmax(out14, dim=1).numpy()
    prob28 = torch.softmax(out28, dim=1).numpy()
    return 0.5 * (prob14 + fold_28_to_14(prob28)), prob28


def export_onnx(model, path, metadata=None):
    """Write the model (softmax outputs ``prob14``, ``prob28``) as ONNX, atomically."""
    import copy

    import onnx
    import torch

    exported = copy.deepcopy(model).eval()
    exported.softmax = True
    sample = [torch.as_tensor(a[None]) for a in skeleton_features(np.zeros((FRAMES, 22, 3)) + np.arange(22)[:, None])]
    tmp = f"{path}.tmp"
    with warnings.catch_warnings():  # the TorchScript exporter warns that it is the legacy one
        warnings.simplefilter("ignore", DeprecationWarning)
        torch.onnx.export(
            exported,
            tuple(sample),
            tmp,
            input_names=["jcd", "slow", "fast"],
            output_names=["prob14", "prob28"],
            dynamic_axes={name: {0: "batch"} for name in ("jcd", "slow", "fast", "prob14", "prob28")},
            opset_version=17,
            dynamo=False,
        )
    proto = onnx.load(tmp)
    for key, value in (metadata or {}).items():
        entry = proto.metadata_props.add()
        entry.key, entry.value = str(key), str(value)
    onnx.save(proto, tmp)
    os.replace(tmp, path)
