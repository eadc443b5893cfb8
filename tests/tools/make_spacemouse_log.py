"""Writes tests/data/spacemouse_push_forward.hidlog, the synthetic SpaceMouse report log the
spacemouse rostest replays (not a recording of a device: no SpaceMouse was at hand).

Timeline (s): 0 the device is open, at rest; 1.0 button 0 pressed (engage); 2.0-3.5 the cap
pushed fully away from the user, repeated every 16 ms as a device does (~62 Hz), with one
truncated report at 2.5; 3.5 back to rest; 4.5 button released; 5.5 end.

Run: .venv/bin/python tests/tools/make_spacemouse_log.py
"""

import os
import struct
import sys

PUSH_START, PUSH_END, PERIOD = 2.0, 3.5, 0.016
HERE = os.path.dirname(os.path.abspath(__file__))
OUTPUT = os.path.join(HERE, "..", "data", "spacemouse_push_forward.hidlog")


def motion(tx, ty, tz, rx=0, ry=0, rz=0):
    """Translation and rotation reports (report ids 1 and 2)."""
    return [bytes([1]) + struct.pack("<3h", tx, ty, tz), bytes([2]) + struct.pack("<3h", rx, ry, rz)]


def lines():
    """The log's lines."""
    out = ["# synthetic SpaceMouse HID report log, written by tests/tools/make_spacemouse_log.py\n"]

    def add(t, report):
        out.append(f"{t:.4f} {report.hex()}\n")

    for report in motion(0, 0, 0):
        add(0.0, report)
    add(1.0, bytes([3, 1, 0]))
    k = 0
    while PUSH_START + k * PERIOD < PUSH_END:
        t = PUSH_START + k * PERIOD
        for report in motion(0, -350, 0):  # HID y points toward the user: away is negative
            add(t, report)
        if abs(t - 2.5) < PERIOD / 2:
            add(t + 0.001, bytes([1, 0, 0]))  # truncated: must be rejected, not crash or move
        k += 1
    for report in motion(0, 0, 0):
        add(PUSH_END, report)
    add(4.5, bytes([3, 0, 0]))
    add(5.5, bytes([0x17, 100]))  # a battery report: ignored
    return out


if __name__ == "__main__":
    path = sys.argv[1] if len(sys.argv) > 1 else OUTPUT
    with open(path, "w", encoding="utf-8") as fh:
        fh.writelines(lines())
    print(f"wrote {path}")
