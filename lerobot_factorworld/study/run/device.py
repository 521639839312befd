"""Which device a training or evaluation may use: refused in one line where the machine lacks it, rather than
run on the CPU as LeRobot's configs quietly do."""

from __future__ import annotations


def device_problem(setting: str, device: str, cuda_count: int, mps: bool) -> str | None:
    """Why ``device`` (the value of ``setting``: ``train.device`` or ``eval.device``) cannot run on a machine with
    ``cuda_count`` CUDA devices and MPS or not; ``None`` where it can."""
    if device.startswith("cuda") and int(device.partition(":")[2] or 0) >= cuda_count:
        return f"{setting}={device} but this machine has {cuda_count} CUDA device(s); use --{setting}=cpu"
    if device == "mps" and not mps:
        return f"{setting}=mps but this machine has no MPS device; use --{setting}=cpu"
    return None


def machine_devices() -> tuple[int, bool]:
    """This machine's CUDA devices and whether it has MPS. Asking CUDA keeps this process from forking workers
    that use it: only a process that runs on the device, or a child Python, should ask."""
    import torch  # noqa: PLC0415 - deliberately here: only a training or evaluating process needs torch (seconds)

    return torch.cuda.device_count(), torch.backends.mps.is_available()


def require_device(setting: str, device: str) -> str:
    """``device``, refused when this process cannot use it, rather than run elsewhere: LeRobot's configs quietly
    fall back to the CPU."""
    if device == "cpu":
        return device
    problem = device_problem(setting, device, *machine_devices())
    if problem:
        raise RuntimeError(problem)
    return device
