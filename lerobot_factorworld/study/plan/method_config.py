"""A study's methods: a LeRobot policy type and its overrides to train, or an existing checkpoint to evaluate.

The settings of one method, checked on their own when the config is read; what needs the whole study (distinct
names and settings, the tasks' families) is :meth:`.config.StudyConfig.validate`'s, and whether LeRobot accepts
the policy settings is :func:`.policy_checks.check_policy`'s (it imports LeRobot: seconds).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ...envs.lerobot_obs import FACTORWORLD_OBS, check_obs_mode
from ...families import family_of
from ...tasks import get_task
from ..run.checkpoint import checkpoint_setting
from ..run.inputs import EPOCHS_OVER, OWN_FRAMES
from .paths import resolve_arg_paths, resolve_policy_paths
from .setting_checks import is_number

METHOD_TRAIN_SETTINGS = ("steps", "epochs", "batch_size", "curve_every", "extends", "extra_args")  # a method's own


def _train_value(method: str, name: str, value: Any) -> Any:
    """A method's own ``train`` value as the study's ``train`` parses it (``20`` -> ``20.0`` epochs), so the
    same settings key the same training whichever of the two holds them."""
    if name == "extra_args":  # lerobot-train runs in the step's folder, as for the study's extra_args
        if not isinstance(value, list) or not all(isinstance(a, str) for a in value):
            raise ValueError(f"method {method!r}: train.extra_args must be a list of flags, got {value!r}")
        return resolve_arg_paths(value)
    if value is None and name == "epochs":
        return None
    if name == "extends":  # budgets, as the study's train.extends holds them (checked with the rest: TrainSettings)
        if not isinstance(value, list) or not all(is_number(b) for b in value):
            raise ValueError(f"method {method!r}: train.extends must be a list of numbers (budgets), got {value!r}")
        return [float(budget) for budget in value]
    whole = name in ("steps", "batch_size")
    if not is_number(value) or (whole and value != int(value)):
        kind = "a whole number" if whole else "a number"
        raise ValueError(f"method {method!r}: train.{name} must be {kind}, got {value!r}")
    return int(value) if whole else float(value)


@dataclass
class MethodConfig:
    """A method: a LeRobot policy type and its overrides, trained on every dataset of the study, e.g.
    ``{name: bc_shift, policy: {type: bc, augmentation: shift}}``; or an existing checkpoint, evaluated as it
    is, e.g. ``{name: my_policy, checkpoint: path/to/pretrained_model}`` (``checkpoint.py``).

    Args:
        name: Name in the results (``method`` column), e.g. ``bc_shift``.
        policy: ``--policy.<key>=<value>`` settings for ``lerobot-train``; ``type`` is required (unless
            ``checkpoint`` is given, which takes none).
        checkpoint: A LeRobot ``pretrained_model`` folder (or a Hub model id, fetched only when the Hub can be
            reached) to evaluate instead of training one: no collection and no training for this method. It
            is evaluated once per task, N and widths, on the environments of the first of ``seeds`` (it has
            no training seed), in the same cells and conditions as the trained methods.
        obs: The observation the checkpoint was made for: ``factorworld`` (``collect.cameras`` at
            ``collect.image_size``, 8-number state) or ``lerobot_metaworld`` (LeRobot's metaworld env:
            docs/lerobot_metaworld.md). Trained methods always observe as their datasets do (``factorworld``).
        extra_tasks: Out-of-domain data (the paper's section 5.4): a trained method's data for a task is that
            task's dataset plus the dataset of each of these other tasks in the same cell (same N, seed and
            widths; a listed task equal to the cell's own is skipped, so ``[pick-place, door-open]`` gives each
            of the two tasks the other's demos). In-task demos and gradient steps stay those of the same method
            without extra tasks (``train.epochs`` counts the task's own frames), so only the data's composition
            changes. Meta-World tasks only (the datasets must share their features).
        extra_demos: Demos of each extra task (``None``: ``collect.demos`` for it, so the datasets are the ones
            those tasks' own cells use, collected once).
        train: This method's own training settings over the study's ``train``, among
            :data:`METHOD_TRAIN_SETTINGS`: e.g. ``{epochs: 20, batch_size: 16}`` for a transformer beside a CNN
            trained 60 epochs at batch 32, in one study on the same datasets. Its training's key holds the
            settings in effect, so a method that overrides nothing keeps its keys. ``steps`` (or ``epochs``, not
            both) trains that many steps even where the study's ``train`` counts epochs (and draws no curve).
        epochs_over: With ``extra_tasks``, what ``train.epochs`` counts: ``task`` (the default) the task's own
            frames, so the gradient steps are those without extra tasks and each own frame is seen fewer times;
            ``merged`` every frame of the merged data, so each own frame is seen as often as without extra tasks,
            in proportionally more gradient steps (F8 in docs/findings.md: at equal steps pick-place's own data got
            13 of the recipe's 60 passes).
    """

    name: str = "rt1_small"
    policy: dict[str, Any] = field(default_factory=dict)
    checkpoint: str | None = None
    obs: str = FACTORWORLD_OBS
    extra_tasks: list[str] = field(default_factory=list)
    extra_demos: int | None = None
    epochs_over: str = OWN_FRAMES
    train: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        check_obs_mode(self.obs)
        unknown = sorted(set(self.train) - set(METHOD_TRAIN_SETTINGS))
        if unknown:
            raise ValueError(
                f"method {self.name!r}: unknown train setting(s) {', '.join(unknown)}; valid: "
                + ", ".join(METHOD_TRAIN_SETTINGS)
            )
        if self.checkpoint is not None and self.train:
            raise ValueError(f"method {self.name!r}: train settings apply to a trained method, not a given checkpoint")
        self.train = {k: _train_value(self.name, k, v) for k, v in self.train.items()}
        if "steps" in self.train and "epochs" in self.train:
            raise ValueError(f"method {self.name!r}: train sets steps or epochs, not both")
        if self.epochs_over not in EPOCHS_OVER:
            raise ValueError(
                f"method {self.name!r}: unknown epochs_over {self.epochs_over!r}; valid: {', '.join(EPOCHS_OVER)}"
            )
        if self.epochs_over != OWN_FRAMES and not self.extra_tasks:
            raise ValueError(
                f"method {self.name!r}: epochs_over={self.epochs_over} counts epochs over merged data: it needs extra_tasks"
            )
        if self.checkpoint is not None and (self.extra_tasks or self.extra_demos is not None):
            raise ValueError(
                f"method {self.name!r}: extra_tasks / extra_demos add training data; a given checkpoint is not trained"
            )
        for task in self.extra_tasks:
            check_extra_task(self.name, task)
        if self.extra_demos is not None and self.extra_demos < 1:
            raise ValueError(f"method {self.name!r}: extra_demos must be at least 1, got {self.extra_demos}")
        if self.checkpoint is not None:
            if self.policy:
                raise ValueError(
                    f"method {self.name!r} names a checkpoint and policy settings {self.policy}: a given checkpoint "
                    "is evaluated as it is (its settings are in its config.json); drop one"
                )
            self.checkpoint = checkpoint_setting(self.checkpoint)
            return
        if "type" not in self.policy:
            raise ValueError(
                f"method {self.name!r} needs policy.type (a LeRobot policy type such as bc, rt1, act) or a "
                "checkpoint (an existing pretrained_model folder)"
            )
        if self.obs != FACTORWORLD_OBS:
            raise ValueError(
                f"method {self.name!r}: obs={self.obs} applies to a given checkpoint only (a trained method observes "
                f"as its dataset does, obs={FACTORWORLD_OBS})"
            )
        # lerobot-train runs in the step's folder: a relative weights path must not depend on that
        self.policy = resolve_policy_paths(self.policy)

    def extra_tasks_for(self, task: str) -> list[str]:
        """The other tasks whose demos join ``task``'s training data (``extra_tasks`` without ``task``)."""
        return [t for t in self.extra_tasks if t != task]

    @property
    def trains(self) -> bool:
        """The study trains this method (it names policy settings, not a checkpoint)."""
        return self.checkpoint is None


def check_extra_task(method: str, task: str, role: str = "extra task") -> None:
    """An out-of-domain task (or a task that gets one: ``role``) exists and is a plain Meta-World task: their
    datasets are merged, which needs the same features."""
    try:
        get_task(task)
    except ValueError as err:  # "unknown task 'x'; valid tasks: ..."
        raise ValueError(f"method {method!r}: extra_tasks: {err}") from None
    if family_of(task).name:  # "" for plain Meta-World tasks
        raise ValueError(
            f"method {method!r}: {role} {task!r} is of the {family_of(task).name} family, whose datasets have other "
            "features than Meta-World tasks'; extra_tasks joins Meta-World tasks only"
        )
