"""The skeleton gesture network (torch; training only, the runtime uses its ONNX export).

DD-Net's layout (Yang et al. 2019): the joint-collection distances and the two motion
scales (``skeleton_features``) each go through pointwise and temporal 1-D convolutions,
are concatenated along channels and go through three temporal blocks with max pooling,
a global max pool and two dense layers. One trunk, two heads: the 14-class gesture and
the 28-class gesture x finger problems, each ending in a softmax in the exported model.
``filters`` sets the width (DD-Net: 16 for its 0.15 M version, 64 for 1.8 M).
"""

import torch
from torch import nn

from motion_sensor.gestures.skeleton_features import FRAMES, JCD_SIZE, MOTION_SIZE

__all__ = ["SkeletonNet"]


def _conv(cin, cout, kernel):
    return nn.Sequential(
        nn.Conv1d(cin, cout, kernel, padding=kernel // 2, bias=False),
        nn.BatchNorm1d(cout),
        nn.LeakyReLU(0.2),
    )


def _branch(cin, filters, pool, dropout):
    layers = [
        _conv(cin, 2 * filters, 1),
        nn.Dropout1d(dropout),
        _conv(2 * filters, filters, 3),
        nn.Dropout1d(dropout),
        _conv(filters, filters, 1),
    ]
    if pool:
        layers.append(nn.MaxPool1d(2))
    layers.append(nn.Dropout1d(dropout))
    return nn.Sequential(*layers)


def _block(cin, cout):
    return nn.Sequential(_conv(cin, cout, 3), _conv(cout, cout, 3))


class SkeletonNet(nn.Module):
    """jcd (N, FRAMES, 231), slow (N, FRAMES, 66), fast (N, FRAMES/2, 66) -> (logits14, logits28)."""

    def __init__(self, filters=32, dropout=0.1, dense=128, softmax=False):
        super().__init__()
        self.softmax = softmax
        self.jcd = _branch(JCD_SIZE, filters, True, dropout)
        self.slow = _branch(MOTION_SIZE, filters, True, dropout)
        self.fast = _branch(MOTION_SIZE, filters, False, dropout)
        self.trunk = nn.Sequential(
            _block(3 * filters, 2 * filters),
            nn.MaxPool1d(2),
            nn.Dropout1d(dropout),
            _block(2 * filters, 4 * filters),
            nn.MaxPool1d(2),
            nn.Dropout1d(dropout),
            _block(4 * filters, 8 * filters),
            nn.Dropout1d(dropout),
        )
        width = 8 * filters
        self.dense = nn.Sequential(
            nn.Linear(width, dense, bias=False),
            nn.BatchNorm1d(dense),
            nn.LeakyReLU(0.2),
            nn.Dropout(0.5),
            nn.Linear(dense, dense, bias=False),
            nn.BatchNorm1d(dense),
            nn.LeakyReLU(0.2),
            nn.Dropout(0.5),
        )
        self.head14 = nn.Linear(dense, 14)
        self.head28 = nn.Linear(dense, 28)
        assert FRAMES % 8 == 0

    def forward(self, jcd, slow, fast):
        x = torch.cat(
            [self.jcd(jcd.transpose(1, 2)), self.slow(slow.transpose(1, 2)), self.fast(fast.transpose(1, 2))], dim=1
        )
        x = self.trunk(x)
        x = torch.amax(x, dim=2)
        x = self.dense(x)
        out14, out28 = self.head14(x), self.head28(x)
        if self.softmax:
            return torch.softmax(out14, dim=1), torch.softmax(out28, dim=1)
        return out14, out28
