"""An onnxruntime session for one of the package's shipped networks, on the CPU with a fixed
number of threads; onnxruntime is imported only when a session is made."""

from motion_sensor.errors import MotionSensorError

__all__ = ["cpu_session"]


def cpu_session(model_path: str, what: str, threads: int = 1):
    """The ``onnxruntime.InferenceSession`` of ``model_path``; a model that cannot be loaded
    raises MotionSensorError naming ``what`` and the file."""
    import onnxruntime

    options = onnxruntime.SessionOptions()
    options.intra_op_num_threads = threads
    options.inter_op_num_threads = 1
    options.log_severity_level = 3
    try:
        return onnxruntime.InferenceSession(model_path, options, providers=["CPUExecutionProvider"])
    except Exception as exc:  # noqa: BLE001 - any unreadable model is the same user error
        raise MotionSensorError(f"{what} {model_path} cannot be loaded: {exc}") from exc
