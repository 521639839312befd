"""``train``: the ``lerobot-train`` settings shared by every method (a method may override some: ``MethodConfig.train``).

A budget, batch size and device are checked on their own when the settings are made; how ``curve_every`` and
``extends`` sit against the budget is :meth:`TrainSettings.check_budgets`'s, which the study calls for its own
settings and each method's (a shorter link of an ``extends`` chain, :meth:`TrainSettings.at_budget`, need not
pass it: its curve is its full budget's).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace
from typing import Any

from ...core.checks import check_at_least
from ..run.inputs import whole_epochs
from .paths import resolve_arg_paths
from .setting_checks import check_device, positive_number


@dataclass
class TrainSettings:
    """``lerobot-train`` settings shared by every method.

    Args:
        steps: Gradient steps (ignored when ``epochs`` is set).
        epochs: Passes over the dataset's frames (the paper: 100); steps = ceil(epochs * frames / batch).
        batch_size: Batch size.
        threads: Torch CPU threads per training run (fixed so that results do not depend on the machine).
        device: ``cpu`` or ``cuda``.
        extra_args: More ``lerobot-train`` flags, e.g. ``["--optimizer.lr=3e-4"]``; values of flags named
            ``*_path`` / ``*_root`` are made absolute (training runs in the step's folder).
        curve_every: A learning curve: a checkpoint every this many epochs (needs ``epochs``; 0, the default:
            none), each evaluated on the ``train`` condition as its own cached step, so P_T is measured against
            training time (``curve.csv``, the report's "Learning curve"). In the training step's key when set.
        extends: Shorter budgets (epochs, or steps without ``epochs``), increasing, that the training passes
            through as steps of their own: the first trains from scratch, each next one continues the one before
            from its saved state, and the full budget continues the last; a cached one is never trained again, so
            a longer budget costs only its new epochs. Each continuing training's key holds the one it continues.
            Exact (the same checkpoints as one run) for a policy without a learning-rate schedule, the only kind
            it is allowed for: a schedule LeRobot builds from ``--steps`` would differ. ``[]``: one run.
    """

    steps: int = 1000
    epochs: float | None = None
    batch_size: int = 32
    threads: int = 1
    device: str = "cpu"
    extra_args: list[str] = field(default_factory=list)
    curve_every: float = 0
    extends: list[float] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.extra_args = resolve_arg_paths(list(self.extra_args))  # training runs in the step's folder
        if self.epochs is None:
            check_at_least("train.steps", self.steps, 1)
        elif not positive_number(self.epochs):
            raise ValueError(f"train.epochs must be a positive number, got {self.epochs!r}")
        check_at_least("train.batch_size", self.batch_size, 1)
        check_device("train.device", self.device)

    def check_budgets(self, where: str = "train") -> None:
        """``curve_every`` and ``extends`` fit the budget (``where``: ``train``, or the method whose own settings
        these are), and ``extends`` trains with a constant learning rate."""
        if self.curve_every and not (
            positive_number(self.curve_every) and self.epochs is not None and self.curve_every < self.epochs
        ):
            raise ValueError(
                f"{where}.curve_every is a number of epochs below {where}.epochs (0: no learning curve), got "
                f"{self.curve_every!r} with epochs {self.epochs!r}"
            )
        budgets = [*self.extends, self.budget()]
        if self.extends and not (
            all(positive_number(b) for b in budgets)
            and all(a < b for a, b in itertools.pairwise(budgets))
            and (self.epochs is not None or all(float(b).is_integer() for b in budgets))
        ):
            unit = "epochs" if self.epochs is not None else "steps (whole numbers)"
            raise ValueError(
                f"{where}.extends is a list of increasing {unit} below {where}.{unit.split()[0]} "
                f"({self.budget()!r}), got {self.extends!r}"
            )
        if self.extends and any(a.startswith(("--scheduler", "--use_policy_training_preset")) for a in self.extra_args):
            raise ValueError(
                f"{where}.extends needs the policy's own (constant) learning rate: a schedule set in extra_args may "
                "depend on --steps, so a continued training would not be the same; drop extends or the scheduler flags"
            )

    def budget(self) -> float:
        """What ``extends`` counts in: ``epochs``, or ``steps`` without epochs."""
        return self.steps if self.epochs is None else self.epochs

    def at_budget(self, budget: float) -> TrainSettings:
        """These settings trained for ``budget`` (one of ``extends``) instead, extending nothing themselves."""
        if self.epochs is None:
            return replace(self, steps=int(budget), extends=[])
        return replace(self, epochs=budget, extends=[])

    def curve_epochs(self) -> list[float]:
        """The learning curve's checkpoints before the last, in nominal epochs (``curve_every`` apart)."""
        if not self.curve_every or self.epochs is None:
            return []
        count = math.ceil(self.epochs / self.curve_every) - 1
        return [whole_epochs(self.curve_every * j) for j in range(1, count + 1)]

    def keyed(self) -> dict[str, Any]:
        """What of these settings a training's key holds (``grid._train_step``): ``steps`` only without
        ``epochs``, no ``curve_every`` when 0; two methods whose policy, data and this are equal are one training."""
        return {
            "steps": self.steps if self.epochs is None else None,
            "epochs": self.epochs,
            "batch_size": self.batch_size,
            "threads": self.threads,
            "device": self.device,
            "extra_args": list(self.extra_args),
            "curve_every": self.curve_every or None,
        }
