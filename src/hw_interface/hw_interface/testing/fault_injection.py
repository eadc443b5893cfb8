"""Fault injection shared by the simulated controllers (``fake_rtde``,
``fake_simple_message``): a fault (an e-stop, a protective stop, a controller error, a
pulled cable) halts the simulated arm at once, without a braking ramp, as a safety stop
does, and stays until it is cleared; clearing it leaves the arm where it halted."""

__all__ = ["FaultInjection"]


class FaultInjection:
    """Mixed into a simulated controller, which provides ``lock`` and ``_halt()`` (stop
    everything now, called with the lock held)."""

    def _inject_fault(self, **state):
        """Set the controller's fault ``state`` (attribute=value) and halt the arm."""
        with self.lock:
            for name, value in state.items():
                setattr(self, name, value)
            self._halt()

    def _clear_fault(self, **state):
        """Set the controller's fault ``state`` back (attribute=value); the arm stays put."""
        with self.lock:
            for name, value in state.items():
                setattr(self, name, value)
