"""``factorworld study --config configs/study/<name>.yaml``: the settings of a generalization-gap study.

A study is the grid methods x tasks x N x seeds, each cell trained on its own dataset and evaluated on
the conditions: ``train``, every factor in ``factors``, the ``pairs``, and the radius sweep (camera and
table position sampled, for training and test alike, from radii 0.025 / 0.05 / 0.075 m). Everything is
checked here, before any work starts.
"""

from __future__ import annotations

import itertools
import json
import logging
import math
import os
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import draccus

from ...core.checks import check_at_least, check_choice
from ...core.io import atomic_write_json
from ...datasets.hub import check_hub_repo_id
from ...envs.lerobot_obs import FACTORWORLD_OBS, LEROBOT_METAWORLD_OBS, check_lerobot_task, check_obs_mode
from ...experts import DEFAULT_ACTION_NOISE
from ...factors.registry import PAPER_STUDY_FACTORS, WIDTHS, check_task_support, get_factor
from ...families import all_families, condition_family, family_of
from ...protocol.conditions import PAIR_SEPARATOR, condition_name, parse_shift
from ...protocol.sampling import DEFAULT_RGB_FRACTION, SamplingOptions
from ...scene.build import DEFAULT_QUALITY, QUALITIES
from ...scene.cameras import DEFAULT_CAMERAS_SETTING, DEFAULT_IMAGE_SIZE
from ...tasks import get_task
from ..run.checkpoint import checkpoint_setting
from ..run.inputs import EPOCHS_OVER, OWN_FRAMES, whole_epochs
from ..sequential import AUTO, StopRule
from .claim_config import ClaimConfig

ALL_PAIRS = "all"
RADIUS_FACTORS = ("camera_pos", "table_pos")
RADII_M = {"narrow": 0.025, "medium": 0.05, "wide": 0.075}  # the paper's radii (appendix table)
PATH_SUFFIXES = ("_path", "_root")  # settings named like this are local paths: resolved when the config is read
WEIGHTS_SUFFIX = "weights_path"  # ... and these name weight files that must exist before a study starts
DEVICE_PATTERN = re.compile(r"cpu|mps|cuda(:\d+)?")


def is_path_setting(name: str) -> bool:
    """A policy setting or ``lerobot-train`` flag that names a local file or folder."""
    return name.endswith(PATH_SUFFIXES)


def absolute_path(value: str) -> str:
    """``value`` made absolute against the directory the command runs from (steps run elsewhere)."""
    return os.path.abspath(os.path.expanduser(value))


def map_policy_paths(policy: dict[str, Any], convert: Callable[[str], str]) -> dict[str, Any]:
    """The policy settings with ``convert`` applied to every path-like value (``*_path``, ``*_root``, nested too)."""
    out: dict[str, Any] = {}
    for name, value in policy.items():
        if isinstance(value, dict):
            out[name] = map_policy_paths(value, convert)
        elif isinstance(value, str) and value and is_path_setting(name):
            out[name] = convert(value)
        else:
            out[name] = value
    return out


def resolve_policy_paths(policy: dict[str, Any]) -> dict[str, Any]:
    """The policy settings with every path-like value made absolute."""
    return map_policy_paths(policy, absolute_path)


def split_flag(arg: str) -> tuple[str, str] | None:
    """``--a.b_path=x`` -> (``a.b_path``, ``x``); ``None`` for anything that is not ``--name=value``."""
    if not arg.startswith("--") or "=" not in arg:
        return None
    name, _, value = arg[2:].partition("=")
    return name, value


def map_arg_paths(args: list[str], convert: Callable[[str], str]) -> list[str]:
    """``lerobot-train`` flags with ``convert`` applied to path-like values (``--x.y_path=...``, ``--x.y_root=...``)."""
    out = []
    for arg in args:
        flag = split_flag(arg)
        if flag and flag[1] and is_path_setting(flag[0]):
            arg = f"--{flag[0]}={convert(flag[1])}"
        out.append(arg)
    return out


def resolve_arg_paths(args: list[str]) -> list[str]:
    """``lerobot-train`` flags with path-like values made absolute."""
    return map_arg_paths(args, absolute_path)


def policy_paths(policy: dict[str, Any], prefix: str = "") -> dict[str, str]:
    """Dotted setting name -> path, for every path-like policy setting (nested too)."""
    out: dict[str, str] = {}
    for name, value in policy.items():
        if isinstance(value, dict):
            out.update(policy_paths(value, f"{prefix}{name}."))
        elif isinstance(value, str) and value and is_path_setting(name):
            out[prefix + name] = value
    return out


def check_device(setting: str, device: str) -> None:
    if not DEVICE_PATTERN.fullmatch(str(device)):
        raise ValueError(f"unknown {setting} {device!r}; valid: cpu, cuda, cuda:<index>, mps")


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
    if name == "extends":  # budgets, as the study's train.extends holds them (checked with the rest: _check_train)
        if not isinstance(value, list) or not all(_is_number(b) for b in value):
            raise ValueError(f"method {method!r}: train.extends must be a list of numbers (budgets), got {value!r}")
        return [float(budget) for budget in value]
    whole = name in ("steps", "batch_size")
    if not _is_number(value) or (whole and value != int(value)):
        kind = "a whole number" if whole else "a number"
        raise ValueError(f"method {method!r}: train.{name} must be {kind}, got {value!r}")
    return int(value) if whole else float(value)


def _is_number(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float)


@dataclass
class MethodConfig:
    """A method: a LeRobot policy type and its overrides, trained on every dataset of the study, e.g.
    ``{name: bc_shift, policy: {type: bc, augmentation: shift}}``; or an existing checkpoint, evaluated as it
    is, e.g. ``{name: my_policy, checkpoint: path/to/pretrained_model}`` (``checkpoint.py``).

    Attributes:
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


def check_policy(method: MethodConfig) -> None:
    """The method's policy type exists and accepts its overrides (as ``lerobot-train`` will parse them)."""
    # Deliberately here: importing LeRobot (and the policy configs that register bc and rt1) costs seconds,
    # and only a study's validation needs it, not every importer of this module.
    import lerobot.policies  # noqa: F401, PLC0415 - registers LeRobot's own policy types (act, diffusion, ...)
    from lerobot.configs.policies import PreTrainedConfig  # noqa: PLC0415

    from ...policies.bc import configuration_bc  # noqa: F401, PLC0415 - registers bc
    from ...policies.rt1 import configuration_rt1  # noqa: F401, PLC0415 - registers rt1

    kind = method.policy["type"]
    if kind not in PreTrainedConfig.get_known_choices():
        known = ", ".join(sorted(PreTrainedConfig.get_known_choices()))
        raise ValueError(f"method {method.name!r}: unknown policy type {kind!r}; valid types: {known}")
    overrides = {k: v for k, v in method.policy.items() if k != "type"}
    # On the CPU: without a device LeRobot's config asks torch.cuda.is_available(), and a process that has asked
    # can no longer fork workers that use CUDA ("Cannot re-initialize CUDA in forked subprocess"). Where the
    # study trains and evaluates is train.device and eval.device, checked where the steps run.
    overrides_cpu = {**overrides, "device": "cpu"}
    quiet = logging.getLogger()
    level, quiet.level = quiet.level, logging.ERROR  # constructing a config logs device warnings
    try:
        draccus.decode(PreTrainedConfig.get_choice_class(kind), overrides_cpu)
    except Exception as err:  # draccus reports unknown fields and bad values; the innermost cause says why
        while err.__cause__ is not None:
            err = err.__cause__
        raise ValueError(f"method {method.name!r}: bad policy settings {overrides}: {err}") from None
    finally:
        quiet.level = level


def per_task_setting(setting: str, values: dict[str, Any]) -> dict[str, Any]:
    """A per-task override (``{task: value}``) keyed by task names, the Meta-World ``-v3`` spelling folded.
    A task the study leaves out is fine (``--tasks`` may narrow a config); an unknown one is refused,
    naming the valid tasks, before any work starts."""
    out = {}
    for task, value in values.items():
        try:
            out[get_task(str(task)).name] = value
        except ValueError as err:  # "unknown task 'x'; valid tasks: ..."
            raise ValueError(f"{setting}: {err}") from None
    return out


@dataclass
class CollectSettings:
    """Scripted demonstrations per (task, N, seed) dataset (``factorworld collect``).

    Attributes:
        demos: Successful demos per dataset (spread evenly over the N environments).
        demos_per_task: Per-task override of ``demos`` (the paper: pick-place 2000, others 1000).
        cameras: Cameras stored and given to the policy.
        image_size: Square image side in pixels (the paper: 84).
        use_videos: Store frames as MP4 (smaller) or PNG in parquet (faster to train from).
        action_noise: Std of the expert's Gaussian action noise.
        max_episode_steps: Demo step limit (``None``: the task's horizon).
        object_pos_width: Range of the per-episode object start (``narrow`` / ``medium``), for
            collection and evaluation alike.
        n_distractors: Distractor objects per environment.
        rgb_fraction: Share of texture draws (object, table, floor, distractors) that are a flat RGB colour
            instead of an image, for collection and evaluation alike (``None``: the sampling default,
            ``SamplingOptions.rgb_fraction``, the paper's images and colours as docs/factors.md reads it).
        n_objects: Objects on the table per scene, for the task families that read it (their
            ``sampling_options``; ``None``: the sampling default); refused for other tasks.
        template: The pick family's fixed phrasing: every episode of the dataset (and of its evaluations in the
            training environments) is phrased with this training template, e.g. ``"pick up the {colour} {noun}"``
            (``None``: a template drawn per episode). In the collection's key only when set.
        quality: Render quality of the demonstrations and so of every evaluation on their environments
            (``fast``, ``lod``: simplified robot meshes, about 2x faster frames, slightly other pixels; ``full``:
            Meta-World's shadows, about 7x slower; docs/factors.md). In the collection's key when not ``fast``.
            The cost model assumes ``fast``.
        workers: Worker processes of one collection.
    """

    demos: int = 50
    demos_per_task: dict[str, int] = field(default_factory=dict)
    cameras: str = DEFAULT_CAMERAS_SETTING
    image_size: int = DEFAULT_IMAGE_SIZE
    use_videos: bool = False
    action_noise: float = DEFAULT_ACTION_NOISE
    max_episode_steps: int | None = None
    object_pos_width: str = "narrow"
    n_distractors: int = 1
    rgb_fraction: float | None = None
    n_objects: int | None = None
    template: str | None = None
    quality: str = DEFAULT_QUALITY
    workers: int = 1

    def __post_init__(self) -> None:
        self.demos_per_task = per_task_setting("collect.demos_per_task", self.demos_per_task)
        check_choice("collect.quality", self.quality, QUALITIES)
        if self.rgb_fraction is not None:
            try:
                SamplingOptions(rgb_fraction=self.rgb_fraction)
            except ValueError as err:  # "rgb_fraction must be in [0, 1], got 2.0"
                raise ValueError(f"collect.{err}") from None

    @property
    def other_quality(self) -> str | None:
        """``quality`` where it is not the default (what a collection's key holds), else ``None``."""
        return None if self.quality == DEFAULT_QUALITY else self.quality

    @property
    def effective_rgb_fraction(self) -> float:
        """``rgb_fraction`` as set, or the sampling default."""
        return DEFAULT_RGB_FRACTION if self.rgb_fraction is None else float(self.rgb_fraction)

    def demos_for(self, task: str) -> int:
        return int(self.demos_per_task.get(get_task(task).name, self.demos))

    def family_options_for(self, task: str) -> dict[str, Any]:
        """The sampling options ``task``'s family reads (``SamplingOptions`` fields named in its
        ``sampling_options``), each as set here or the sampling default; ``{}`` for a plain task."""
        defaults, family = SamplingOptions(), family_of(task)
        return {
            name: getattr(defaults, name) if getattr(self, name) is None else getattr(self, name)
            for name in family.sampling_options
            if getattr(self, name) is not None or name not in family.keyed_when_set  # keys as before it existed
        }


@dataclass
class TrainSettings:
    """``lerobot-train`` settings shared by every method.

    Attributes:
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

    def __post_init__(self) -> None:
        self.extra_args = resolve_arg_paths(list(self.extra_args))

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


def _check_train(train: TrainSettings, where: str) -> None:
    """A training's settings are usable (``where``: ``train``, or the method whose own settings these are)."""
    if train.epochs is None:
        check_at_least(f"{where}.steps", train.steps, 1)
    elif not _positive_number(train.epochs):
        raise ValueError(f"{where}.epochs must be a positive number, got {train.epochs!r}")
    if train.curve_every and not (
        _positive_number(train.curve_every) and train.epochs is not None and train.curve_every < train.epochs
    ):
        raise ValueError(
            f"{where}.curve_every is a number of epochs below {where}.epochs (0: no learning curve), got "
            f"{train.curve_every!r} with epochs {train.epochs!r}"
        )
    check_at_least(f"{where}.batch_size", train.batch_size, 1)
    budgets = [*train.extends, train.budget()]
    if train.extends and not (
        all(_positive_number(b) for b in budgets)
        and all(a < b for a, b in itertools.pairwise(budgets))
        and (train.epochs is not None or all(float(b).is_integer() for b in budgets))
    ):
        unit = "epochs" if train.epochs is not None else "steps (whole numbers)"
        raise ValueError(
            f"{where}.extends is a list of increasing {unit} below {where}.{unit.split()[0]} "
            f"({train.budget()!r}), got {train.extends!r}"
        )
    if train.extends and any(a.startswith(("--scheduler", "--use_policy_training_preset")) for a in train.extra_args):
        raise ValueError(
            f"{where}.extends needs the policy's own (constant) learning rate: a schedule set in extra_args may depend "
            "on --steps, so a continued training would not be the same; drop extends or the scheduler flags"
        )


def check_extendable(method: MethodConfig, train: TrainSettings) -> None:
    """A training that ``extends`` shorter ones continues them exactly only when its learning rate does not depend on
    the budget: refused for a policy whose training preset has a schedule (LeRobot builds it from ``--steps``)."""
    import lerobot.policies  # noqa: F401, PLC0415 - LeRobot's policy types (seconds), as check_policy imports them
    from lerobot.configs.policies import PreTrainedConfig  # noqa: PLC0415

    overrides = {k: v for k, v in method.policy.items() if k != "type"}
    config = draccus.decode(PreTrainedConfig.get_choice_class(method.policy["type"]), {**overrides, "device": "cpu"})
    scheduler = config.get_scheduler_preset()
    if train.extends and scheduler is not None:
        raise ValueError(
            f"method {method.name!r}: train.extends needs a learning rate that does not depend on the budget, but "
            f"policy type {method.policy['type']!r} trains with a {type(scheduler).__name__} schedule built from "
            "--steps: train it in one run (drop extends)"
        )


def _positive_number(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float) and math.isfinite(value) and value > 0


@dataclass
class EvalSettings:
    """Evaluation of every checkpoint on every condition (LeRobot's ``eval_policy_all``).

    Attributes:
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


def write_run_config(path: str | Path, settings: dict[str, Any]) -> None:
    """A study's settings as JSON (which YAML reads too) in the one format its folder and docs/results/ use."""
    atomic_write_json(path, settings, indent=1, sort_keys=True, default=str)


# the benchmark dataset a profile's Hub results name (not on the Hub yet)
HUB_BENCHMARK = "lerobot-factorworld/factor-world"


@dataclass
class StudyConfig:
    """A generalization-gap study: the experiment grid and the claims it tests. Every setting here can change
    what a step computes; how the grid runs (workers, executor, dry-run, ...) is :class:`..run.options.RunOptions`,
    and a study's YAML file or command line holds both (:class:`.command.StudyCommand`).

    Attributes:
        name: Study name (in results and report).
        out_dir: Study folder: ``results.csv``, ``report.md``, plots, and the cached steps (``steps/``).
        tasks: Tasks.
        n_train_envs: The N values (training environments per dataset).
        seeds: Seeds; seed ``s`` samples the training and test environments and seeds training.
        train_factors: Factors varied across the training environments (the paper's seven).
        factors: Single-factor conditions; also the conditions a task family adds (its ``conditions``,
            e.g. held-out phrasings and objects), which stand alone: no pairs, no training factor.
        pairs: Pair conditions: ``[all]`` (every pair of the factors in ``factors``) or a list of ``a+b``.
        radius_factors: Factors of the radius sweep (``camera_pos``, ``table_pos``).
        radius_widths: Widths of the sweep: narrow / medium / wide = radius 0.025 / 0.05 / 0.075 m.
        methods: Methods (policy types and overrides).
        collect: Demonstration settings.
        train: Training settings.
        eval: Evaluation settings.
        claims: The paper's claims this study tests (``claim_config.py``): the report decides each from its
            intervals (``claims.py``). None: the paper's factor ordering over ``factors``.
        finding: The paper's finding this study is one of several studies of (``F2``, ``F8``, ...): its report
            decides its claims together with those of the other studies of the same finding beside its folder,
            with one Holm correction for all of them and shared cells decided once. Empty: this study alone.
        hub_benchmark: The Hub benchmark dataset (``user/name``) a profile's ``.eval_results`` entries name and
            its ``eval.yaml`` describes (``results/eval_results.py``). The default is not on the Hub yet.
    """

    name: str = "study"
    out_dir: str = "outputs/study"
    tasks: list[str] = field(default_factory=lambda: ["door-open"])
    n_train_envs: list[int] = field(default_factory=lambda: [5])
    seeds: list[int] = field(default_factory=lambda: [0])
    train_factors: list[str] = field(default_factory=lambda: list(PAPER_STUDY_FACTORS))
    factors: list[str] = field(default_factory=lambda: list(PAPER_STUDY_FACTORS))
    pairs: list[str] = field(default_factory=list)
    radius_factors: list[str] = field(default_factory=list)
    radius_widths: list[str] = field(default_factory=lambda: list(WIDTHS))
    methods: list[MethodConfig] = field(
        default_factory=lambda: [MethodConfig("rt1_small", {"type": "rt1", "preset": "small"})]
    )
    collect: CollectSettings = field(default_factory=CollectSettings)
    train: TrainSettings = field(default_factory=TrainSettings)
    eval: EvalSettings = field(default_factory=EvalSettings)
    claims: list[ClaimConfig] = field(default_factory=list)
    finding: str = ""
    hub_benchmark: str = HUB_BENCHMARK

    def __post_init__(self) -> None:
        self.methods = [m if isinstance(m, MethodConfig) else MethodConfig(**m) for m in self.methods]
        self.claims = [c if isinstance(c, ClaimConfig) else ClaimConfig(**c) for c in self.claims]
        self.validate()

    # --- derived -----------------------------------------------------------------------------

    def only(self, names: Sequence[str]) -> StudyConfig:
        """This grid with only the methods ``names``: a part of the study run on its own (another machine trains
        one method) and merged with the rest by ``factorworld merge-results``. Their steps keep the keys they have
        in the whole grid (a key holds its own method's settings, never the list of methods); the claims about a
        method left out go too (a claim that names none is the first method's, and a baseline is one)."""
        known = [m.name for m in self.methods]
        unknown = [n for n in names if n not in known]
        if unknown or not names:
            given = ", ".join(unknown) or "(none given)"
            raise ValueError(f"only_methods: unknown method(s) {given}; this study's methods: {', '.join(known)}")
        owned = [c if c.method else replace(c, method=known[0]) for c in self.claims]
        claims = [c for c in owned if c.method in names and c.baseline in (None, *names)]
        return replace(self, methods=[m for m in self.methods if m.name in names], claims=claims)

    def trained_methods(self) -> list[MethodConfig]:
        """The methods the study trains (policy settings): they need the collections and trainings."""
        return [m for m in self.methods if m.trains]

    def given_methods(self) -> list[MethodConfig]:
        """The methods that name an existing checkpoint: evaluated only."""
        return [m for m in self.methods if not m.trains]

    def train_for(self, method: MethodConfig) -> TrainSettings:
        """The training settings ``method`` trains with: the study's ``train`` with the method's own ``train``
        over them (``steps`` clears the study's ``epochs`` and ``curve_every``)."""
        own = dict(method.train)
        if "steps" in own:  # a number of steps: no epochs, so no curve or epochs to extend unless the method asks
            own = {"epochs": None, "curve_every": 0, "extends": [], **own}
        return replace(self.train, **own) if own else self.train

    def curve_methods(self) -> list[MethodConfig]:
        """The trained methods with a learning curve (their ``train.curve_every``)."""
        return [m for m in self.trained_methods() if self.train_for(m).curve_every]

    def family_conditions(self) -> list[str]:
        """The task families' own conditions listed in ``factors`` (e.g. held-out phrasings / objects)."""
        return [f for f in self.factors if condition_family(f) is not None]

    def shifted_factors(self) -> list[str]:
        """The factors of ``factors`` (without the families' conditions)."""
        return [f for f in self.factors if condition_family(f) is None]

    def pair_conditions(self) -> list[str]:
        if [p.strip() for p in self.pairs] == [ALL_PAIRS]:
            return [condition_name(p) for p in itertools.combinations(self.shifted_factors(), 2)]
        return [condition_name(parse_shift(p)) for p in self.pairs]

    def conditions(self) -> list[str]:
        """The shifted conditions of the main grid (singles, then pairs)."""
        return [*self.factors, *self.pair_conditions()]

    def radius_variants(self) -> list[tuple[str, str]]:
        """(factor, width) runs of the sweep whose width differs from the factor's default (those
        reuse the main grid)."""
        return [
            (factor, width)
            for factor in self.radius_factors
            for width in self.radius_widths
            if width != get_factor(factor).default_width
        ]

    # --- checks ------------------------------------------------------------------------------

    def validate(self) -> None:
        if not self.tasks or not self.n_train_envs or not self.seeds or not self.methods:
            raise ValueError("a study needs at least one task, one N (n_train_envs), one seed and one method")
        self._validate_conditions()
        self._validate_methods()
        for claim in self.claims:
            claim.validate([m.name for m in self.methods], self.tasks, self.shifted_factors(), self.pair_conditions())
        if self.finding and not re.fullmatch(r"[A-Za-z0-9_.-]+", self.finding):
            raise ValueError(f"finding must be a short name such as F8 (letters, digits, _ . -), got {self.finding!r}")
        check_hub_repo_id(self.hub_benchmark, "hub_benchmark")
        for factor in self.radius_factors:
            if factor not in RADIUS_FACTORS:
                raise ValueError(f"the radius sweep applies to {', '.join(RADIUS_FACTORS)}, got {factor!r}")
            if factor not in self.factors:
                raise ValueError(
                    f"radius factor {factor!r} must also be in factors (its narrow radius is the main grid)"
                )
        for width in self.radius_widths:
            if width not in RADII_M:
                raise ValueError(f"unknown radius width {width!r}; valid: {', '.join(RADII_M)}")
        get_factor("object_pos").range(self.collect.object_pos_width)  # raises naming the valid widths
        self._validate_family_options()
        check_device("train.device", self.train.device)
        check_device("eval.device", self.eval.device)
        if min(self.n_train_envs) < 1 or len(set(self.n_train_envs)) != len(self.n_train_envs):
            raise ValueError(f"n_train_envs must be distinct positive numbers, got {self.n_train_envs}")
        if len(set(self.seeds)) != len(self.seeds):
            raise ValueError(f"seeds must be distinct, got {self.seeds}")
        self._validate_episodes()
        _check_train(self.train, "train")
        for method in self.trained_methods():
            if method.train:
                _check_train(self.train_for(method), f"method {method.name!r}: train")
        for method in self.trained_methods():  # last: importing LeRobot's policy configs takes seconds
            check_policy(method)
            if self.train_for(method).extends:
                check_extendable(method, self.train_for(method))

    def _validate_conditions(self) -> None:
        """Factors apply to every task and are varied in training; a family's conditions need its tasks."""
        duplicates = sorted({f for f in self.factors if self.factors.count(f) > 1})
        if duplicates:
            raise ValueError(f"factors lists {', '.join(duplicates)} more than once")
        for condition in self.family_conditions():
            condition_family(condition).check_condition(condition, self.tasks)  # "applies to the x family only"
        shifted = self.shifted_factors()
        for task in self.tasks:
            check_task_support(get_task(task), [*self.train_factors, *shifted, *self.radius_factors])
        unknown = [f for f in shifted if f not in self.train_factors]
        if unknown and self.trained_methods():  # a given checkpoint's training is not this study's
            raise ValueError(
                f"factor(s) {unknown} are shifted but not varied in training (train_factors: {self.train_factors})"
            )
        for pair in self.pairs:
            named = [part.strip() for part in pair.split(PAIR_SEPARATOR)]
            if any(condition_family(part) is not None for part in named):
                own = [c for family in all_families() for c in family.conditions]
                raise ValueError(f"pair {pair!r}: the conditions {', '.join(own)} stand alone (list them in factors)")
        for pair in self.pair_conditions():
            if any(f not in shifted for f in pair.split(PAIR_SEPARATOR)):
                raise ValueError(f"pair {pair!r} names a factor that is not in factors {shifted}")

    def _validate_methods(self) -> None:
        """Each method is a valid policy, named once, with settings no other method has (one train key each);
        a given checkpoint is named once per observation, and LeRobot's observation needs Meta-World tasks.
        (Their policy settings are checked last, by ``validate``.)"""
        if any(m.obs == LEROBOT_METAWORLD_OBS for m in self.methods):
            for task in self.tasks:
                check_lerobot_task(get_task(task))  # "the pick family has no LeRobot counterpart"
        names = [m.name for m in self.methods]
        if len(set(names)) != len(names):
            twice = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"method names must be distinct: {', '.join(twice)} given more than once")
        for method in self.trained_methods():
            for task in self.tasks if method.extra_tasks else ():
                check_extra_task(method.name, task, "with extra_tasks, task")
            if method.epochs_over != OWN_FRAMES and self.train_for(method).epochs is None:
                raise ValueError(
                    f"method {method.name!r}: epochs_over={method.epochs_over} says what train.epochs counts; "
                    "set train.epochs instead of train.steps"
                )
        seen: dict[str, str] = {}
        for method in self.trained_methods():
            data = {"extra_tasks": sorted(method.extra_tasks), "extra_demos": method.extra_demos}
            data["epochs_over"] = method.epochs_over
            data["train"] = self.train_for(method).keyed()
            settings = json.dumps({"policy": method.policy, **data}, sort_keys=True)
            if settings in seen:
                raise ValueError(
                    f"methods {seen[settings]!r} and {method.name!r} have the same policy settings {method.policy}, "
                    "training settings and training data: "
                    "they would train one checkpoint; drop one or change its settings"
                )
            seen[settings] = method.name
        given: dict[tuple[str, str], str] = {}
        for method in self.given_methods():
            same = given.setdefault((method.checkpoint, method.obs), method.name)
            if same != method.name:
                raise ValueError(
                    f"methods {same!r} and {method.name!r} name the same checkpoint {method.checkpoint} with the same "
                    f"obs={method.obs}: they would be one evaluation; drop one"
                )

    def _validate_family_options(self) -> None:
        """A family's sampling option (``collect.n_objects``) is set only for tasks of families that read
        it, and within the range ``SamplingOptions`` accepts."""
        for family in all_families():
            for name in family.sampling_options:
                value = getattr(self.collect, name)
                if value is None:
                    continue
                others = [t for t in self.tasks if name not in family_of(t).sampling_options]
                if others:
                    raise ValueError(
                        f"collect.{name} applies to the {family.name} family only, not to {', '.join(others)}"
                    )
                try:
                    SamplingOptions(**{name: value})
                except ValueError as err:
                    raise ValueError(f"collect.{err}") from None

    def missing_weight_files(self) -> list[str]:
        """``method 'x': <setting> <path>`` for every weights file a method names that does not exist."""
        missing = []
        for method in self.methods:
            for name, path in policy_paths(method.policy).items():
                if name.endswith(WEIGHTS_SUFFIX) and not Path(path).is_file():
                    missing.append(f"method {method.name!r}: {name} {path}")
        owners = [("train.extra_args", self.train.extra_args)]
        owners += [
            (f"method {m.name!r}: train.extra_args", m.train["extra_args"])
            for m in self.methods
            if "extra_args" in m.train
        ]
        for owner, args in owners:
            for arg in args:
                flag = split_flag(arg)
                if flag and flag[0].endswith(WEIGHTS_SUFFIX) and not os.path.isfile(flag[1]):
                    missing.append(f"{owner}: {flag[0]} {flag[1]}")
        return missing

    def check_weight_files(self) -> None:
        """Refuse to start when a weights file is missing (weights are never downloaded)."""
        missing = self.missing_weight_files()
        if missing:
            raise FileNotFoundError(
                f"weights file(s) not found: {'; '.join(missing)} (weights are never downloaded: put the files "
                "there or fix the paths, relative to the directory you run from)"
            )

    def _validate_episodes(self) -> None:
        ev = self.eval
        if ev.auto:
            self._validate_auto()
        per = f"eval.block={ev.stop_rule().block}" if ev.auto else f"eval.episodes={ev.episodes}"
        if (not ev.auto and ev.episodes < 1) or ev.n_test_envs < 1 or ev.batch_size < 1:
            raise ValueError("eval.episodes, eval.n_test_envs and eval.batch_size must be at least 1")
        count = ev.stop_rule().block if ev.auto else ev.episodes
        for n in self.n_train_envs:
            if ev.n_test_envs % n:
                raise ValueError(
                    f"eval.n_test_envs={ev.n_test_envs} must be a multiple of every N (got N={n}), so that each "
                    "test environment is paired with the training environment the same episode sees"
                )
            if count % n:
                raise ValueError(f"{per} must be a multiple of every N (got N={n})")
        for task, limit in ev.max_episode_steps_per_task.items():  # known tasks (per_task_setting)
            if int(limit) < 1:
                raise ValueError(f"eval.max_episode_steps_per_task[{task}] must be at least 1, got {limit}")
        if ev.max_episode_steps is not None and ev.max_episode_steps < 1:
            raise ValueError(f"eval.max_episode_steps must be at least 1, got {ev.max_episode_steps}")
        if count % ev.n_test_envs:
            raise ValueError(
                f"{per} must be a multiple of eval.n_test_envs={ev.n_test_envs}, so that every "
                "test environment is visited equally"
            )
        for task in self.tasks if self.trained_methods() else ():  # demos are collected for training only
            if self.collect.demos_for(task) < max(self.n_train_envs):
                raise ValueError(
                    f"{task}: {self.collect.demos_for(task)} demos cannot cover N={max(self.n_train_envs)} environments"
                )

    def _validate_auto(self) -> None:
        """``eval.episodes=auto`` stops each checkpoint's evaluation on its own anytime-valid intervals: refused
        where the study's claims rest on fixed-n intervals that such a stopping makes invalid."""
        self.eval.stop_rule()  # block, budget, tolerance and level: "must be a positive multiple of ..."
        why = (
            "eval.episodes=auto stops each checkpoint's evaluation on its own anytime-valid intervals, which "
            "leaves {what} without a valid interval: give eval.episodes a number"
        )
        if len(self.seeds) > 1:
            raise ValueError(why.format(what=f"the claims over seeds {self.seeds} (fixed-n seed-level bootstraps)"))
        if self.claims:
            raise ValueError(why.format(what="the config's claims (decided on fixed-n bootstrap intervals)"))
        if self.curve_methods():
            raise ValueError(why.format(what="the learning curve (fixed-n intervals per checkpoint)"))
        if not self.conditions():
            raise ValueError("eval.episodes=auto stops shifted conditions once decided: list at least one factor")
