"""The compute setting both policies offer as ``speed`` (``--policy.speed=default|fast``).

- ``default``: today's computation, bit for bit: float32 everywhere, and each encoder's input in the layout it
  has always had (bc: the default contiguous NCHW; rt1: its FiLM-EfficientNet has always made its normalised
  input channels-last). Every existing result and cached step was made this way.
- ``fast``: the image encoder's input in channels-last layout and the policy's whole forward (the training loss
  and action selection alike) under bfloat16 autocast on the input's device; the loss and the actions are
  float32 again. On this project's CPU (AVX-512 BF16) one update of bc's CNN (batch 32, 84 px, one thread)
  measured 72 ms in float32, 60 ms channels-last, 47 ms in bf16 autocast and 34 ms with both (issue 42);
  ``scripts/bench_policy.py`` measures both policies side by side. rt1's Lite trunks keep their depthwise
  convolutions in float32 on CPU (:func:`float32_on_cpu`): in bf16 their backward is several times slower,
  and rt1 ``small`` was slower under ``fast`` than under ``default`` until they did. A CPU without native
  bf16 emulates it and may be slower.
  On a GPU ``fast`` measured slower than ``default`` (0.86-0.90x for both policies on an H200; docs/rt1.md, "On a
  GPU"): these models are bound by kernel launches there, and autocast adds casts.

One setting rather than a layout field plus a precision field: the two gains come together, and a layout
field's default could not describe both policies (rt1's encoder input is already channels-last by default).
Its own setting rather than LeRobot's ``use_amp``: in LeRobot 0.6.1 ``use_amp`` gives bf16 autocast on CPU in
``lerobot-train`` (through Accelerate) and ``lerobot-eval``, but not where ``eval_policy_all`` or the policy
is called directly (the study's evaluation, the benchmarks), and on CUDA it means float16 with a gradient
scaler; ``speed`` behaves the same wherever the policy runs, and is saved with its config.

The weights keep their default layout under either value: with a channels-last input PyTorch's CPU
convolution already computes channels-last (converting the weights too measured no faster), and channels-last
weights would give Adam channels-last moments, which LeRobot's optimizer checkpoint (safetensors
``save_file``) refuses. So a checkpoint holds the same tensors whichever value trained it, and loads under
either.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable

import torch
from torch import Tensor

SPEEDS = ("default", "fast")


def check_speed(speed: str) -> None:
    """A one-line ValueError naming the valid values, for anything but ``default`` or ``fast``."""
    if speed not in SPEEDS:
        raise ValueError(
            f"unknown speed {speed!r}; valid: {', '.join(SPEEDS)} "
            "(default: float32, as every existing result; fast: channels-last input and bfloat16 autocast)"
        )


def is_fast(speed: str) -> bool:
    return speed == "fast"


def compute_context(speed: str, device: torch.device | str) -> contextlib.AbstractContextManager:
    """bfloat16 autocast on ``device``'s type for ``fast``; nothing at all for ``default``."""
    if not is_fast(speed):
        return contextlib.nullcontext()
    return torch.autocast(device_type=torch.device(device).type, dtype=torch.bfloat16)


def encoder_input(images: Tensor, speed: str) -> Tensor:
    """Images (N, C, H, W) as the encoder takes them: channels-last for ``fast``, untouched for ``default``."""
    return images.contiguous(memory_format=torch.channels_last) if is_fast(speed) else images


def as_float32(x: Tensor, speed: str) -> Tensor:
    """Outputs of an autocast region back in float32 (``fast``); ``default`` returns ``x`` itself."""
    return x.float() if is_fast(speed) else x


def float32_on_cpu(fn: Callable[[Tensor], Tensor], x: Tensor) -> Tensor:
    """``fn(x)``, but in float32 when bf16 autocast is on for a CPU tensor (``fn(x)`` itself otherwise).

    For depthwise convolutions: on this CPU one forward and backward of a bf16 depthwise convolution (48
    channels, 3x3, 21 px, batch 96, one thread) took 27.5 ms against 4.2 ms in float32, the backward to the
    input being the slow part, which made rt1's ``small`` preset slower under ``fast`` until they stayed float32.
    """
    if x.device.type != "cpu" or not torch.is_autocast_enabled("cpu"):
        return fn(x)
    with torch.autocast("cpu", enabled=False):
        return fn(x.float())
