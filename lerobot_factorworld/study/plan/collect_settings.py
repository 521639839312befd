"""``collect``: how the scripted demonstrations of every (task, N, seed) dataset are made (``factorworld collect``).

Checked on their own when the config is read; a family's option (``n_objects``, ``template``) is checked by
:meth:`.config.StudyConfig.validate`, which knows the tasks: set for a task of another family, that is the
error to name, not its value.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ...core.checks import check_choice
from ...experts import DEFAULT_ACTION_NOISE
from ...factors.registry import get_factor
from ...families import family_of
from ...protocol.sampling import DEFAULT_RGB_FRACTION, SamplingOptions
from ...scene.build import DEFAULT_QUALITY, QUALITIES
from ...scene.cameras import DEFAULT_CAMERAS_SETTING, DEFAULT_IMAGE_SIZE
from ...tasks import get_task
from .setting_checks import per_task_setting


@dataclass
class CollectSettings:
    """Scripted demonstrations per (task, N, seed) dataset (``factorworld collect``).

    Args:
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
        get_factor("object_pos").range(self.object_pos_width)  # raises naming the valid widths

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
