"""A contact sheet: one task rendered under every applicable factor, several values each.

Row 0 is the default scene; each further row shifts one factor (values drawn from the held-out split
and the factor's widest range, so differences are easy to see). The object's start is pinned so that
each row differs from the default only by its factor.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from PIL import Image, ImageDraw
from tqdm import tqdm

from .core.checks import check_at_least, check_image_size, check_output_file, check_seed
from .core.splits import check_split
from .envs.factor_env import FactorWorldEnv
from .factors.registry import FACTORS, supported_factors
from .factors.values import FactorValues, SceneConfig
from .protocol.sampling import SamplingOptions, factor_rng, sample_factor
from .scene.build import DEFAULT_QUALITY, check_quality
from .scene.cameras import DEFAULT_CAMERAS, check_cameras
from .tasks import check_tasks, get_task

LABEL_WIDTH = 150
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".webp")  # formats PIL writes from an RGB image


@dataclass
class ContactSheetConfig:
    """``factorworld contact-sheet``: render a task under every factor.

    Attributes:
        task: Task name (``factorworld tasks`` lists them).
        n_values: Values shown per factor.
        image_size: Side of each rendered image in pixels.
        camera: Camera to render (``factorworld cameras`` lists them).
        quality: ``fast``, ``full`` or ``lod`` rendering (``scene.build.QUALITIES``).
        seed: Seed for the factor values.
        split: Asset split to draw discrete values from.
        out: Output PNG path.
    """

    task: str = "pick-place"
    n_values: int = 4
    image_size: int = 128
    camera: str = DEFAULT_CAMERAS[0]
    quality: str = DEFAULT_QUALITY
    seed: int = 0
    split: str = "eval"
    out: str = "outputs/contact_sheet.png"

    def __post_init__(self) -> None:
        (self.task,) = check_tasks([self.task])
        check_at_least("n_values", self.n_values, 1)
        check_image_size(self.image_size)
        (self.camera,) = check_cameras([self.camera], "camera")
        check_quality(self.quality)
        check_seed(self.seed)
        check_split(self.split)
        check_output_file(self.out, "out", IMAGE_SUFFIXES)


def contact_sheet_rows(cfg: ContactSheetConfig) -> list[tuple[str, list[SceneConfig]]]:
    """(row label, configurations) for the default scene and each factor that applies to the task."""
    task = get_task(cfg.task)
    pinned = FactorValues(object_pos=(0.0, 0.0))
    rows = [("default scene", [SceneConfig(task.name, pinned)])]
    for name in supported_factors(task):
        spec = FACTORS[name]
        widest = list(spec.ranges)[-1] if spec.ranges else None
        options = SamplingOptions(widths={name: widest} if widest else {})
        rng = factor_rng(cfg.seed, cfg.split, name)
        configs = []
        for _ in range(cfg.n_values):
            value = sample_factor(name, task, rng, cfg.split, options)
            configs.append(SceneConfig(task.name, pinned.set(**{name: value}), split=cfg.split))
        rows.append((spec.title, configs))
    return rows


def render_contact_sheet(cfg: ContactSheetConfig) -> Path:
    rows = contact_sheet_rows(cfg)
    size = cfg.image_size
    sheet = Image.new("RGB", (LABEL_WIDTH + size * cfg.n_values, size * len(rows)), "white")
    draw = ImageDraw.Draw(sheet)
    env = FactorWorldEnv(cfg.task, cameras=(cfg.camera,), image_size=size, quality=cfg.quality, scene_cache_size=1)
    try:
        total = sum(len(configs) for _, configs in rows)
        with tqdm(total=total, desc=f"contact sheet {cfg.task}", unit="scene") as bar:
            for r, (label, configs) in enumerate(rows):
                draw.text((6, r * size + size // 2 - 6), label, fill="black")
                for c, config in enumerate(configs):
                    obs, _ = env.reset(seed=cfg.seed, options={"config": config})
                    sheet.paste(Image.fromarray(obs["pixels"][cfg.camera]), (LABEL_WIDTH + c * size, r * size))
                    bar.update()
    finally:
        env.close()
    out = Path(cfg.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(out)
    return out
