"""Textures as the paper samples them: images and flat RGB colours in [0, 1]^3 (docs/factors.md), settable in
collection, LeRobot's evaluation and the study; and the object's pixel footprint (scene/footprint.py)."""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest

from lerobot_factorworld.factors.registry import FACTORS, parse_rgb
from lerobot_factorworld.factors.values import FactorValues, SceneConfig, SceneObject
from lerobot_factorworld.protocol.sampling import DEFAULT_RGB_FRACTION, SamplingOptions, sample_configs, shift_configs
from lerobot_factorworld.scene.footprint import PixelCounter, object_pixels, visible_geoms
from lerobot_factorworld.tasks import get_task

ROOT = Path(__file__).resolve().parents[1]
TEXTURE_FACTORS = ("object_texture", "table_texture", "floor_texture")
PAPER_FACTORS = ("camera_pos", "table_pos", *TEXTURE_FACTORS, "light")


def _colours(names) -> list[tuple[float, float, float]]:
    return [parse_rgb(n) for n in names if n.startswith("rgb:")]


def _texture_values(configs) -> list[str]:
    """Every texture of the configurations: the three texture factors and the distractors'."""
    out = [getattr(c.factors, f) for c in configs for f in TEXTURE_FACTORS if getattr(c.factors, f) is not None]
    return out + [d.texture for c in configs for d in c.factors.distractors or ()]


# --- the share and where it applies -------------------------------------------------------------


def test_default_share_is_one_half_and_the_docs_say_so():
    assert SamplingOptions().rgb_fraction == DEFAULT_RGB_FRACTION == 0.5
    assert [f for f in FACTORS.values() if f.asset_kind == "texture"] == [FACTORS[f] for f in TEXTURE_FACTORS]
    docs = (ROOT / "docs" / "factors.md").read_text()
    assert "## Textures: images and flat colours" in docs and "rgb_fraction=0.5" in docs


@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan")])
def test_a_share_outside_the_unit_interval_is_refused(value):
    with pytest.raises(ValueError, match=r"rgb_fraction must be in \[0, 1\], got"):
        SamplingOptions(rgb_fraction=value)


def test_every_texture_factor_and_distractor_texture_honours_the_share():
    factors = (*TEXTURE_FACTORS, "distractors")
    for share, expected in ((1.0, True), (0.0, False)):
        options = SamplingOptions(rgb_fraction=share, n_distractors=2)
        train = sample_configs("door-open", 8, seed=2, factors=factors, options=options)
        tests = shift_configs(train, factors, 8, seed=2, options=options)
        values = _texture_values(train + tests)
        assert len(values) == 16 * 5 and {v.startswith("rgb:") for v in values} == {expected}
    options = SamplingOptions(n_distractors=2)  # the default share: both kinds, about half each
    values = _texture_values(sample_configs("door-open", 100, seed=0, factors=factors, options=options))
    share = np.mean([v.startswith("rgb:") for v in values])
    assert abs(share - 0.5) < 5 * np.sqrt(0.25 / len(values)), share  # 5 sigma of 500 draws


def test_colours_replace_images_without_moving_any_stream():
    """A colour takes the place of the image the same draw gives at share 0: the images that stay, and every
    other factor, are identical (the share changes only the values it turns into colours)."""
    factors = (*TEXTURE_FACTORS, "light", "distractors")
    images = sample_configs("pick-place", 30, seed=4, factors=factors, options=SamplingOptions(rgb_fraction=0.0))
    mixed = sample_configs("pick-place", 30, seed=4, factors=factors, options=SamplingOptions(rgb_fraction=0.5))
    kept = 0
    for a, b in zip(images, mixed, strict=True):
        assert a.factors.light == b.factors.light
        for name in TEXTURE_FACTORS:
            if not getattr(b.factors, name).startswith("rgb:"):
                assert getattr(a.factors, name) == getattr(b.factors, name)
                kept += 1
        for x, y in zip(a.factors.distractors, b.factors.distractors, strict=True):
            assert (x.shape, x.x, x.y, x.yaw, x.size) == (y.shape, y.x, y.y, y.yaw, y.size)
    assert 20 < kept < 70  # of 90: both kinds occur


# --- held-out colours come from the evaluation stream --------------------------------------------


@pytest.mark.parametrize("factor", TEXTURE_FACTORS)
def test_colours_are_in_the_unit_cube_and_held_out_ones_differ_from_training_ones(factor):
    options = SamplingOptions(rgb_fraction=1.0)
    for seed in (0, 7):
        train = sample_configs("pick-place", 40, seed=seed, factors=PAPER_FACTORS, options=options)
        tests = shift_configs(train, factor, 40, seed=seed, options=options)  # the held-out (eval) split
        seen = _colours(getattr(c.factors, factor) for c in train)
        held_out = _colours(getattr(c.factors, factor) for c in tests)
        assert len(seen) == len(held_out) == 40
        for rgb in seen + held_out:
            assert len(rgb) == 3 and all(0.0 <= v <= 1.0 for v in rgb)
        assert not set(seen) & set(held_out)  # other draws, not the training colours again
        assert len(set(held_out)) == 40
        # they are the factor's evaluation stream: what sampling the eval split with the same seed draws
        evals = sample_configs("pick-place", 40, seed=seed, split="eval", factors=(factor,), options=options)
        if factor == "floor_texture":  # no rule ties the floor to another factor: the very same values
            assert held_out == _colours(c.factors.floor_texture for c in evals)
    # the colours spread over the cube (uniform draws), in the training and in the held-out stream
    drawn = sample_configs("door-open", 300, 1, "eval", ("table_texture",), options)
    cube = np.array(_colours(c.factors.table_texture for c in drawn))
    assert np.all(np.abs(cube.mean(axis=0) - 0.5) < 0.06) and np.all(cube.min(axis=0) < 0.02)


# --- settable everywhere -------------------------------------------------------------------------


def test_collect_takes_and_records_the_share(tmp_path):
    from lerobot_factorworld.core.settings import parse_config
    from lerobot_factorworld.datasets.collect import CollectConfig, plan_jobs

    args = ["--task=door-open", "--n_envs=3", "--demos=3", f"--root={tmp_path / 'd'}", "--factors=[table_texture]"]
    cfg = parse_config(CollectConfig, [*args, "--sampling.rgb_fraction=1"], "collect")
    assert cfg.sampling.rgb_fraction == 1.0 and cfg.fingerprint()["sampling"]["rgb_fraction"] == 1.0
    assert all(job.config["factors"]["table_texture"].startswith("rgb:") for job in plan_jobs(cfg))
    default = parse_config(CollectConfig, args, "collect")
    assert default.fingerprint()["sampling"]["rgb_fraction"] == DEFAULT_RGB_FRACTION


def _fake_dataset(root: Path, rgb_fraction: float, data_version: int) -> Path:
    """A dataset side-car as ``factorworld collect`` writes it (all an env config reads of a dataset)."""
    options = SamplingOptions(rgb_fraction=rgb_fraction)
    configs = sample_configs("door-open", 2, seed=0, factors=("table_texture", "light"), options=options)
    settings = {
        "task": "door-open",
        "n_envs": 2,
        "factors": ["table_texture", "light"],
        "seed": 0,
        "sampling": {**vars(options), "widths": {}},
        "data_version": data_version,
    }
    (root / "meta").mkdir(parents=True)
    sidecar = {"settings": settings, "environments": [c.to_dict() for c in configs]}
    (root / "meta" / "factorworld.json").write_text(json.dumps(sidecar))
    return root


def test_lerobot_env_config_takes_the_share_and_a_dataset_keeps_its_own(tmp_path):
    import draccus

    from lerobot_factorworld.adapters.env_config import FactorWorldEnvConfig

    args = ["--task=door-open", "--n_train_envs=2", "--n_test_envs=4", "--shifts=[table_texture]"]
    cfg = draccus.parse(
        FactorWorldEnvConfig, args=[*args, "--train_factors=[table_texture]", "--sampling.rgb_fraction=1"]
    )
    suites = cfg.suites("door-open")
    assert cfg.sampling.rgb_fraction == 1.0
    assert all(c.factors.table_texture.startswith("rgb:") for suite in suites.values() for c in suite)
    # a dataset collected before colours existed (data version 2 recorded rgb_fraction=0): read as it was made
    old = _fake_dataset(tmp_path / "old", rgb_fraction=0.0, data_version=2)
    env_cfg = FactorWorldEnvConfig(task="door-open", dataset_root=str(old), shifts=["table_texture"], n_test_envs=4)
    assert env_cfg.sampling.rgb_fraction == 0.0
    # a side-car that does not record the cameras, image size or quality: the env's defaults, and any given is kept
    assert (env_cfg.cameras, env_cfg.image_size, env_cfg.quality) == ("front", 84, "fast")
    given = FactorWorldEnvConfig(task="door-open", dataset_root=str(old), image_size=128, quality="lod")
    assert (given.image_size, given.quality) == (128, "lod")
    shifted = env_cfg.suites("door-open")["table_texture"]
    assert not any(c.factors.table_texture.startswith("rgb:") for c in shifted)
    with pytest.raises(ValueError, match="disagrees with dataset"):  # a share given must agree with the data's
        FactorWorldEnvConfig(task="door-open", dataset_root=str(old), sampling=SamplingOptions(rgb_fraction=1.0))
    new = _fake_dataset(tmp_path / "new", rgb_fraction=1.0, data_version=3)
    env_cfg = FactorWorldEnvConfig(task="door-open", dataset_root=str(new), shifts=["table_texture"], n_test_envs=4)
    assert all(c.factors.table_texture.startswith("rgb:") for c in env_cfg.suites("door-open")["table_texture"])


def _study(**collect):
    from lerobot_factorworld.study.plan.collect_settings import CollectSettings
    from lerobot_factorworld.study.plan.config import StudyConfig
    from lerobot_factorworld.study.plan.eval_settings import EvalSettings

    return StudyConfig(
        tasks=["door-open"],
        n_train_envs=[2],
        train_factors=["light", "table_texture"],
        factors=["table_texture"],
        methods=[{"name": "bc", "policy": {"type": "bc"}}],
        collect=CollectSettings(demos=2, **collect),
        eval=EvalSettings(n_test_envs=2, episodes=2),
    )


def test_the_study_passes_the_share_to_collection_and_so_to_evaluation(tmp_path):
    from lerobot_factorworld.study.plan.grid import make_plan
    from lerobot_factorworld.study.run.collect_step import collect_config
    from lerobot_factorworld.study.run.eval_env import eval_env_config
    from lerobot_factorworld.study.run.inputs import CollectInputs, EvalInputs

    plan = make_plan(_study(rgb_fraction=0.25))
    collect = plan.of_kind("collect")[0]
    assert collect.inputs["rgb_fraction"] == 0.25
    inputs = CollectInputs.from_dict(collect.inputs)
    assert inputs.sampling_options().rgb_fraction == 0.25
    cfg = collect_config(collect.inputs, tmp_path / "data", collect.key)
    assert cfg.sampling == inputs.sampling_options()  # what the dataset records ...
    default = make_plan(_study()).of_kind("collect")[0]
    assert default.inputs["rgb_fraction"] == DEFAULT_RGB_FRACTION and default.key != collect.key
    evals = plan.of_kind("eval")
    assert evals and all(collect.key in s.deps for s in evals)  # ... and every evaluation of it depends on it
    # ... and evaluation reads: its env config takes the dataset's sampling, colours and all
    root = _fake_dataset(tmp_path / "ds", rgb_fraction=0.25, data_version=3)
    shifted = next(EvalInputs.from_dict(s.inputs) for s in evals if s.inputs["condition"] == "table_texture")
    assert eval_env_config(inputs, str(root), shifted).sampling.rgb_fraction == 0.25
    with pytest.raises(ValueError, match=r"collect.rgb_fraction must be in \[0, 1\], got 2"):
        _study(rgb_fraction=2.0)


# --- rendering: a flat colour is what the scene shows ---------------------------------------------


def test_a_flat_colour_paints_the_table_and_the_object(make_env):
    def frames(share):
        options = SamplingOptions(rgb_fraction=share)
        configs = sample_configs("pick-place", 1, seed=3, factors=("object_texture", "table_texture"), options=options)
        env = make_env("pick-place", configs, cameras=("front",))
        obs, _ = env.reset(seed=0)
        return configs[0], env, obs["pixels"]["front"]

    (config, env, colour), (_, _, image) = frames(1.0), frames(0.0)
    model = env.model
    for material, value in (("table_wood", config.factors.table_texture), ("fw_object", config.factors.object_texture)):
        mat = model.material(material)
        assert value.startswith("rgb:")
        assert model.mat_texid[mat.id, int(mujoco.mjtTextureRole.mjTEXROLE_RGB)] == -1  # no image: a flat colour
        assert np.allclose(model.mat_rgba[mat.id, :3], parse_rgb(value), atol=1e-6)
    assert np.abs(colour.astype(int) - image.astype(int)).mean() > 5  # the scene looks different
    # MuJoCo draws a geom in its own rgba unless that is the default: the painted geoms carry the colour too
    painted = np.flatnonzero(model.geom_matid == model.material("fw_object").id)
    assert np.allclose(model.geom_rgba[painted, :3], parse_rgb(config.factors.object_texture), atol=1e-6)
    # the object's pixels show the sampled colour under the light (which scales it and adds grey): its channels
    # keep their order where none is clipped
    geoms = visible_geoms(model, get_task("pick-place").object_bodies)
    with PixelCounter(model, [84]) as counter:
        mask = counter.masks(env.data, "front", geoms)[84]
    pixels = colour[mask].astype(float)
    pixels = pixels[pixels.max(axis=1) < 255]
    assert len(pixels) >= 3
    rgb = np.asarray(parse_rgb(config.factors.object_texture))
    assert all(list(np.argsort(p)) == list(np.argsort(rgb)) for p in pixels)


def test_a_flat_colour_on_pick_objects_keeps_each_objects_own_colour(make_env):
    options = SamplingOptions(rgb_fraction=1.0)
    configs = sample_configs("pick", 1, seed=0, factors=("object_texture",), options=options)
    env = make_env("pick", configs, cameras=("front",))
    obs, _ = env.reset(seed=0)
    assert obs["pixels"]["front"].std() > 0
    from lerobot_factorworld.pick.catalog import get_object
    from lerobot_factorworld.pick.scene import body_name

    model = env.model
    for item in configs[0].content.objects:
        geom = visible_geoms(model, [body_name(item.name)])[0]
        rgba = model.mat_rgba[model.geom_matid[geom]]
        own = np.asarray(get_object(item.name).rgb)
        scale = rgba[:3] / np.where(own > 0, own, 1.0)
        assert np.allclose(scale[own > 0], scale[own > 0][0], atol=1e-6)  # a shade of the object's colour
        assert 0.5 - 1e-9 <= scale[own > 0][0] <= 1.0 + 1e-9


# --- the object's pixel footprint -----------------------------------------------------------------


def test_object_footprint_counts_the_painted_geoms_and_scales_with_the_image_area(make_env):
    env = make_env("pick-place", SceneConfig("pick-place", FactorValues(object_texture="rgb:0.2,0.8,0.3")))
    env.reset(seed=1)
    model, data = env.model, env.data
    geoms = visible_geoms(model, get_task("pick-place").object_bodies)
    painted = np.flatnonzero(model.geom_matid == model.material("fw_object").id)
    assert sorted(geoms) == sorted(painted.tolist())  # the geoms the object-texture factor paints
    with PixelCounter(model, [84, 168]) as counter:
        counts = counter.count(data, "front", geoms)
    assert 5 <= counts[84] <= 60  # a puck in the corner of the table: a few dozen pixels at most
    assert 3.0 <= counts[168] / counts[84] <= 5.0  # four times the area, about four times the pixels
    assert object_pixels(model, data, get_task("pick-place").object_bodies, "front", 84) == counts[84]
    with pytest.raises(ValueError, match="no body 'nothing'"):
        visible_geoms(model, ["nothing"])
    with pytest.raises(ValueError, match=r"image sizes must be in \[1, 480\]"):
        PixelCounter(model, [84, 1000])


def test_a_flat_colour_paints_a_distractor(make_env):
    colour = "rgb:0.9500,0.9000,0.0500"
    item = SceneObject("proc:box-003", 0.25, -0.2, 0.5, 0.12, colour)
    env = make_env("door-open", SceneConfig("door-open", FactorValues(distractors=(item,))))
    obs, _ = env.reset(seed=0)
    model = env.model
    geoms = visible_geoms(model, ["fw_distractor0"])
    assert np.allclose(model.geom_rgba[list(geoms), :3], parse_rgb(colour))
    with PixelCounter(model, [84]) as counter:
        mask = counter.masks(env.data, "front", geoms)[84]
    assert mask.sum() > 20
    mean = obs["pixels"]["front"][mask].astype(float).mean(axis=0)
    assert mean[0] > 2 * mean[2] and mean[1] > 2 * mean[2]  # yellow, not the white the geom rgba once forced
