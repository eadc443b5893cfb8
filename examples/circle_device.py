"""A worked example of a hand device: a synthetic hand that holds still, draws circles, and leaves.

Copy this file to start the driver of your own hand tracker (a glove, a motion-capture
system, a new camera). Every device is one class derived from
``motion_sensor.devices.device.HandDevice``: ``open()``, ``read(now)`` returning a
``HandSample`` (or None when there is nothing new), ``close()``, and a ParamSchema of its
parameters. The shared node wrapper does everything else: parameters (checked, with units),
polling at ``rate_hz`` or blocking reads, waiting for the session to be ready, reconnecting
with backoff when ``open``/``read`` raise ``DeviceUnavailable`` or ``OSError``, /diagnostics
counters, and the ``~finished`` topic once a finite source raises ``EndOfStream``.

Run a session with it (from the project root):

    PYTHONPATH=$PWD/examples scripts/teleop_sim device:=circle_device:CircleDevice

It then runs as the node ``device_node`` (motion_sensor's generic ``device_node``). For a
device of your own in your own package, add a three-line executable instead:
``run_device_node(MyDevice, "my_driver")`` from ``motion_sensor.devices.device_node``.
"""

import math

import numpy as np

from motion_common.params import Param, ParamSchema
from motion_sensor.devices.device import HandDevice, empty_sample
from motion_sensor.errors import EndOfStream
from motion_sensor.hand_sample import HandSample

__all__ = ["CircleDevice"]


class CircleDevice(HandDevice):
    """A right palm, facing down, 0.2 m above the origin of frame ``leap``: still for
    ``hold_s`` (so the clutch engages), then ``turns`` circles of ``radius_m`` in the
    horizontal plane at ``period_s`` each, then out of view for 0.5 s, and the end."""

    name = "circle"  # hardware_id in /diagnostics
    default_frame_id = "leap"
    rate_hz = 100.0  # the wrapper calls read() at this rate; None: read() blocks for each sample
    # A source that ends (EndOfStream): the wrapper then publishes ~finished, which ends the
    # session. A live tracker leaves this False.
    finite = True
    # A synthetic source has no moment of arrival: stamp each sample as it is published.
    stamp_on_publish = True
    params = ParamSchema(
        [
            Param("radius_m", 0.05, "m", "circle radius", low=0.0, high=0.3, low_open=True),
            Param("period_s", 4.0, "s", "time for one circle", low=0.5, high=60.0),
            Param("turns", 2, "", "circles before the hand leaves", low=1, high=1000),
            Param("hold_s", 2.0, "s", "still hand before the first circle", low=0.0, high=60.0),
        ]
    )

    def open(self):
        # A real device connects here; raise DeviceUnavailable to be retried with backoff.
        self.started = None
        self.counters["frames"] = 0

    def read(self, now):
        if self.started is None:
            self.started = now
        t = now - self.started
        circling = t - self.config["hold_s"]
        duration = self.config["turns"] * self.config["period_s"]
        if circling > duration + 0.5:
            raise EndOfStream("circles done")
        self.counters["frames"] += 1
        if circling > duration:
            return empty_sample(now, self.frame_id, self.name)
        angle = 2.0 * math.pi * max(0.0, circling) / self.config["period_s"]
        radius = self.config["radius_m"]
        position = np.array([radius * (math.cos(angle) - 1.0), radius * math.sin(angle), 0.2])
        return HandSample(
            stamp=now,
            position=position,
            orientation=np.array([0.0, 0.0, 0.0, 1.0]),
            frame_id=self.frame_id,
            device=self.name,
            confidence=1.0,
        )

    def close(self):
        pass
