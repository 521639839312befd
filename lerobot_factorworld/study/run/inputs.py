"""The inputs of each kind of step, typed: built by ``plan/grid.py``, read by the step kinds (``*_step.py``) and
``plan/cost.py``.

A step's key hashes ``to_dict()`` of its inputs (``Step.inputs``), so ``to_dict`` gives exactly the
JSON the key has always hashed: the same names, and optional entries left out when unset (a family's
sampling options for tasks of other families, ``n_test_envs`` for the ``train`` condition, a render ``quality``
at the default, an evaluation's ``batch_size`` of one), so that adding one keeps every earlier key.
``from_dict`` is the one reader of a stored step's inputs: a missing or unknown entry is an error
naming it, not a silent default.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

from ...envs.lerobot_obs import CAMERA as LEROBOT_CAMERA
from ...envs.lerobot_obs import FACTORWORLD_OBS, LEROBOT_METAWORLD_OBS
from ...envs.lerobot_obs import IMAGE_SIZE as LEROBOT_IMAGE_SIZE
from ...protocol.conditions import TRAIN_SUITE
from ...protocol.sampling import SamplingOptions
from ...scene.build import DEFAULT_QUALITY


def whole_epochs(value: float) -> float | int:
    """``20.0`` -> ``20``: epochs as configs, keys and a learning curve's labels write them."""
    return int(value) if float(value).is_integer() else value


def _without_unset(out: dict[str, Any], optional: frozenset[str]) -> dict[str, Any]:
    """``out`` without the optional entries left unset (None), so that adding one keeps every earlier key."""
    return {k: v for k, v in out.items() if k not in optional or v is not None}


def _from_dict(cls, data: Mapping[str, Any], extra: str | None = None):
    """``cls(**data)``, refusing unknown names (except into ``extra``) and naming missing ones."""
    names = {f.name for f in fields(cls) if f.name != extra}
    optional = {f.name for f in fields(cls) if f.name in cls.OPTIONAL}
    missing = sorted(names - optional - set(data))
    if missing:
        raise ValueError(f"{cls.__name__}: missing step input(s) {', '.join(missing)}")
    known = {k: v for k, v in data.items() if k in names}
    rest = {k: v for k, v in data.items() if k not in names}
    if rest and extra is None:
        raise ValueError(f"{cls.__name__}: unknown step input(s) {', '.join(sorted(rest))}")
    return cls(**known, **({extra: rest} if extra else {}))


@dataclass(frozen=True)
class CollectInputs:
    """One dataset of scripted demonstrations (``factorworld collect``)."""

    OPTIONAL: ClassVar[frozenset[str]] = frozenset({"quality"})

    task: str
    n_envs: int
    seed: int
    train_factors: tuple[str, ...]  # sorted: each factor has its own RNG, the order changes nothing
    demos: int
    cameras: str
    image_size: int
    use_videos: bool
    action_noise: float
    max_episode_steps: int | None
    n_distractors: int
    rgb_fraction: float  # share of texture draws that are flat RGB colours (the evaluation reads it from the data)
    widths: Mapping[str, str]  # object_pos width and the run's radius widths
    data_version: int
    versions: Mapping[str, str]
    family_options: Mapping[str, Any] = field(default_factory=dict)  # the task family's sampling options
    quality: str | None = None  # the render quality when not the default (``fast``, None: left out of the key)

    @property
    def render_quality(self) -> str:
        """The quality its frames are rendered at (``quality``, or the default when unset)."""
        return self.environments().render_quality

    def to_dict(self) -> dict[str, Any]:
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "family_options"}
        out.update(train_factors=list(self.train_factors), widths=dict(self.widths), versions=dict(self.versions))
        out.update(self.family_options)  # at the top level, as keys have always held them
        return _without_unset(out, self.OPTIONAL)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> CollectInputs:
        out = _from_dict(cls, data, extra="family_options")
        return _replace_seq(out, "train_factors")

    def sampling_options(self) -> SamplingOptions:
        """How the collection draws its environments; its dataset records them, and the evaluation of every
        checkpoint trained on it reads them from there (its ``train`` and shifted conditions alike)."""
        return self.environments().sampling_options()

    def environments(self, obs: str = FACTORWORLD_OBS) -> EnvInputs:
        """The environments this collection runs in, observed as ``obs``: what a given checkpoint is evaluated
        in, in the same cell (the same ``train`` environments, hence the same shifted ones). LeRobot's
        observation has its own camera and image size."""
        lerobot = obs == LEROBOT_METAWORLD_OBS
        return EnvInputs(
            task=self.task,
            n_envs=self.n_envs,
            seed=self.seed,
            train_factors=self.train_factors,
            obs=obs,
            cameras=LEROBOT_CAMERA if lerobot else self.cameras,
            image_size=LEROBOT_IMAGE_SIZE if lerobot else self.image_size,
            n_distractors=self.n_distractors,
            rgb_fraction=self.rgb_fraction,
            widths=dict(self.widths),
            family_options=dict(self.family_options),
            quality=None if lerobot else self.quality,  # LeRobot's observation renders at Meta-World's own quality
        )


@dataclass(frozen=True)
class EnvInputs:
    """The environments of an evaluation that has no dataset (a given checkpoint): the ``train`` condition is
    the N environments sampled as a collection with these settings would sample them, observed as ``obs``."""

    OPTIONAL: ClassVar[frozenset[str]] = frozenset({"family_options", "quality"})

    task: str
    n_envs: int
    seed: int
    train_factors: tuple[str, ...]  # sorted, as a collection's
    obs: str  # factorworld or lerobot_metaworld (envs/lerobot_obs.py)
    cameras: str
    image_size: int
    n_distractors: int
    rgb_fraction: float
    widths: Mapping[str, str]
    family_options: Mapping[str, Any] = field(default_factory=dict)
    quality: str | None = None  # as a collection's: None is the observation's default, left out of the key

    @property
    def render_quality(self) -> str:
        """The quality Factor World's observation renders at (LeRobot's renders at Meta-World's own)."""
        return DEFAULT_QUALITY if self.quality is None else self.quality

    def to_dict(self) -> dict[str, Any]:
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out.update(train_factors=list(self.train_factors), widths=dict(self.widths))
        out["family_options"] = dict(self.family_options)
        return _without_unset(out, self.OPTIONAL)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> EnvInputs:
        return _replace_seq(_from_dict(cls, data), "train_factors")

    def sampling_options(self) -> SamplingOptions:
        """How the environments are drawn (widths, distractors, flat-colour share, the family's options)."""
        return SamplingOptions(
            widths=dict(self.widths),
            n_distractors=self.n_distractors,
            rgb_fraction=self.rgb_fraction,
            **dict(self.family_options),
        )


# What ``train.epochs`` counts when other tasks' data joins a task's (``MethodConfig.epochs_over``): the task's own
# frames (the default, left out of the key) or every frame of the merged data.
OWN_FRAMES, MERGED_FRAMES = "task", "merged"
EPOCHS_OVER = (OWN_FRAMES, MERGED_FRAMES)


@dataclass(frozen=True)
class TrainInputs:
    """One ``lerobot-train`` run of a method on a dataset."""

    OPTIONAL: ClassVar[frozenset[str]] = frozenset({"epochs_over", "curve_every", "extends"})

    policy: Mapping[str, Any]  # path-like settings naming a file replaced by its content hash
    seed: int
    steps: int | None  # None when ``epochs`` is set
    epochs: float | None
    batch_size: int
    threads: int
    device: str
    extra_args: tuple[str, ...]
    versions: Mapping[str, str]
    epochs_over: str | None = None  # "merged", or None (the task's own frames; not in the key)
    curve_every: float | None = None  # epochs between the learning curve's checkpoints; None: no curve, not in the key
    # The budget (epochs, or steps without epochs) of the shorter training this one continues (``train.extends``; its
    # key is a dependency of this one's); None: trained from scratch, not in the key
    extends: float | None = None

    def to_dict(self) -> dict[str, Any]:
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out.update(policy=dict(self.policy), extra_args=list(self.extra_args), versions=dict(self.versions))
        return _without_unset(out, self.OPTIONAL)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> TrainInputs:
        return _replace_seq(_from_dict(cls, data), "extra_args")


@dataclass(frozen=True)
class EvalInputs:
    """One condition of one checkpoint (LeRobot's evaluation): a trained one (its train step is a dependency,
    its dataset gives the environments) or a given one (``checkpoint``, the content hash of its files, and
    ``environments``; the step has no dependency)."""

    OPTIONAL: ClassVar[frozenset[str]] = frozenset(
        {"n_test_envs", "checkpoint", "environments", "batch_size", "checkpoint_epochs", "sequential"}
    )

    condition: str
    episodes: int
    start_seed: int
    max_episode_steps: int | None
    device: str
    versions: Mapping[str, str]
    n_test_envs: int | None = None  # None (and not in the key) for ``train``: the dataset's own environments
    checkpoint: str | None = None  # a given checkpoint's content hash (``checkpoint.py``); None: a trained one
    environments: EnvInputs | None = None  # a given checkpoint's environments; None: its dataset's
    # Vectorised environments when more than one: a batch of frames changes the actions' last bits. None: one
    # at a time, left out of the key, so every evaluation run one at a time keeps the key it always had.
    batch_size: int | None = None
    # A learning curve's checkpoint of the training, in nominal epochs (``TrainSettings.curve_every``); None: the
    # last checkpoint (not in the key, as always)
    checkpoint_epochs: float | None = None
    # ``eval.episodes=auto``: the stopping rule's settings and the group's shifted conditions (``blocks.py``);
    # ``episodes`` is then the budget. None: a fixed number of episodes, not in the key.
    sequential: Mapping[str, Any] | None = None

    def __post_init__(self) -> None:
        if self.batch_size is not None and self.batch_size < 2:
            raise ValueError(f"an evaluation's batch_size is None (one at a time) or at least 2, not {self.batch_size}")
        if (self.condition == TRAIN_SUITE) != (self.n_test_envs is None):
            raise ValueError(f"n_test_envs is set for every shifted condition and only for them ({self.condition})")
        if self.checkpoint_epochs is not None and (self.condition != TRAIN_SUITE or self.checkpoint is not None):
            raise ValueError("a learning curve's checkpoint is evaluated on the train condition of a trained policy")
        if (self.checkpoint is None) != (self.environments is None):
            raise ValueError("a given checkpoint's evaluation names both its checkpoint and its environments")
        if isinstance(self.environments, Mapping):  # read back from a stored step
            object.__setattr__(self, "environments", EnvInputs.from_dict(self.environments))

    def to_dict(self) -> dict[str, Any]:
        """Optional entries left out when unset: a trained checkpoint's evaluation keeps the key it always had."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["versions"] = dict(self.versions)
        if self.environments is not None:
            out["environments"] = self.environments.to_dict()
        return _without_unset(out, self.OPTIONAL)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> EvalInputs:
        return _from_dict(cls, data)


INPUTS = {"collect": CollectInputs, "train": TrainInputs, "eval": EvalInputs}


def _replace_seq(inputs, name: str):
    """A JSON list read back as the tuple the frozen dataclass holds."""
    object.__setattr__(inputs, name, tuple(getattr(inputs, name)))
    return inputs


def inputs_of(kind: str, data: Mapping[str, Any]) -> CollectInputs | TrainInputs | EvalInputs:
    """The typed inputs of a step of ``kind`` from its stored (key) dict."""
    return INPUTS[kind].from_dict(data)
