"""``eval``: how every checkpoint is evaluated on every condition (LeRobot's ``eval_policy_all``).

Checked on their own when the config is read; what depends on the study's N, seeds, claims and curves (episodes
a multiple of every N, then of ``n_test_envs``, so that a count that misses both is told the N first;
``episodes: auto`` only where no fixed-n interval is reported) is :meth:`.config.StudyConfig.validate`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ...core.checks import check_at_least
from ...tasks import get_task
from ..sequential import AUTO, StopRule
from .setting_checks import check_device, per_task_setting


@dataclass
class EvalSettings:
    """Evaluation of every checkpoint on every condition (LeRobot's ``eval_policy_all``).

    Args:
        n_test_envs: Test environments per shifted condition (the paper: 100); a multiple of every N.
        episodes: Episodes per condition; a multiple of every N and of ``n_test_envs``.
        start_seed: Episode ``i`` is reset with ``start_seed + i`` in every condition (paired).
        max_episode_steps: Step limit of an episode (``None``: the task's horizon).
        max_episode_steps_per_task: Per-task override of ``max_episode_steps`` (e.g. ``{bin-picking: 500}``:
            bin-picking's policies finish later than the other tasks', docs/findings.md); the other tasks'
            evaluations, and their keys, stay as they are.
        device: Where the policy runs during evaluation (``cpu``, ``cuda``, ``cuda:<index>``, ``mps``);
            in the step's key (GPU kernels need not give the CPU's actions bit for bit).
        batch_size: Vectorised environments per evaluation. In the key when above 1 (a batch changes the
            actions' last bits, though not the quick study's successes, and is slower on CPU: docs/study.md,
            Throughput); 1 (one at a time) keeps every key it always had.
        threads: Torch CPU threads per evaluation (not in the key).
        record_episodes: Episodes per condition and checkpoint whose frames are kept as videos (the first ones:
            episode i of every condition starts the object at the same place), for report.html's paired
            viewer; 0: none. Not in the key (frames change no result): a step cached without videos keeps none.
        block, max_episodes, tolerance, confidence: With ``episodes: auto`` (``study/sequential.py``): paired
            episodes per block (default ``n_test_envs``), the budget per condition, the gap band a condition may
            stop inside, and the simultaneous level of the anytime-valid intervals. In the keys only with ``auto``.
    """

    n_test_envs: int = 10
    episodes: int | str = 20
    start_seed: int = 1000
    max_episode_steps: int | None = None
    max_episode_steps_per_task: dict[str, int] = field(default_factory=dict)
    device: str = "cpu"
    batch_size: int = 1
    threads: int = 1
    record_episodes: int = 3
    block: int | None = None
    max_episodes: int = 200
    tolerance: float = 0.1
    confidence: float = 0.95

    def __post_init__(self) -> None:
        check_at_least("eval.record_episodes", self.record_episodes, 0)
        if self.episodes != AUTO and (isinstance(self.episodes, bool) or not isinstance(self.episodes, int)):
            raise ValueError(f"eval.episodes must be a whole number or {AUTO}, got {self.episodes!r}")
        self.max_episode_steps_per_task = per_task_setting(
            "eval.max_episode_steps_per_task", self.max_episode_steps_per_task
        )
        check_device("eval.device", self.device)
        if self.auto:
            self.stop_rule()  # block, budget, tolerance and level: "must be a positive multiple of ..."
        if (not self.auto and self.episodes < 1) or self.n_test_envs < 1 or self.batch_size < 1:
            raise ValueError("eval.episodes, eval.n_test_envs and eval.batch_size must be at least 1")
        for task, limit in self.max_episode_steps_per_task.items():  # known tasks (per_task_setting)
            if int(limit) < 1:
                raise ValueError(f"eval.max_episode_steps_per_task[{task}] must be at least 1, got {limit}")
        if self.max_episode_steps is not None and self.max_episode_steps < 1:
            raise ValueError(f"eval.max_episode_steps must be at least 1, got {self.max_episode_steps}")

    def round(self) -> tuple[str, int]:
        """The episodes a condition runs at a time, and the setting that says so (``eval.episodes=20``, or
        ``eval.block=10`` with ``auto``): a multiple of every N and of ``n_test_envs``."""
        if self.auto:
            return f"eval.block={self.stop_rule().block}", self.stop_rule().block
        return f"eval.episodes={self.episodes}", int(self.episodes)

    def max_steps_for(self, task: str) -> int | None:
        return self.max_episode_steps_per_task.get(get_task(task).name, self.max_episode_steps)

    @property
    def auto(self) -> bool:
        """Episodes in blocks until each condition is decided (``episodes: auto``)."""
        return self.episodes == AUTO

    @property
    def budget(self) -> int:
        """Episodes a condition may take at most: ``episodes``, or ``max_episodes`` with ``auto``."""
        return self.max_episodes if self.auto else int(self.episodes)

    def stop_rule(self) -> StopRule:
        """The rule of ``auto`` (its settings checked)."""
        return StopRule(self.block or self.n_test_envs, self.max_episodes, self.tolerance, self.confidence)
