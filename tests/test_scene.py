"""Rendered scenes: every factor visibly changes every task it applies to; the model holds the values
the configuration asked for; the same seeds give the same pixels."""

import mujoco
import numpy as np
import pytest

from lerobot_factorworld import TASKS, FactorValues, SceneConfig, SceneObject
from lerobot_factorworld.assets import load_texture, split_names
from lerobot_factorworld.factors.registry import FACTORS, factor_range, supported_factors
from lerobot_factorworld.protocol.sampling import factor_rng, sample_factor
from lerobot_factorworld.scene.build import DEFAULT_HEADLIGHT, TABLE_CENTER, TEXTURE_SIZE
from lerobot_factorworld.scene.cameras import CAMERAS
from lerobot_factorworld.tasks import get_task

PINNED = FactorValues(object_pos=(0.0, 0.0))


def shifted_value(task: str, name: str):
    """A value clearly different from the default: the corner of the widest range, or an eval asset."""
    spec = FACTORS[name]
    if spec.kind in ("vector", "scalar"):
        low, high = factor_range(get_task(task), name, list(spec.ranges)[-1])
        value = tuple(high) if name != "light" else (0.8, 0.2)
        return value[0] if spec.kind == "scalar" else value
    return sample_factor(name, task, factor_rng(0, "eval", name), "eval")


FAST_TASKS = ("pick-place", "door-open", "pick")  # a free object, an articulated fixture, a task family


@pytest.mark.parametrize(
    "task", [task if task in FAST_TASKS else pytest.param(task, marks=pytest.mark.slow) for task in TASKS]
)
def test_every_applicable_factor_changes_the_image(task, make_env):
    env = make_env(task, image_size=64, scene_cache_size=1)
    default, _ = env.reset(seed=0, options={"config": SceneConfig(task, PINNED)})
    base = default["pixels"]["front"].astype(int)
    for name in supported_factors(task):
        config = SceneConfig(task, PINNED.set(**{name: shifted_value(task, name)}))
        obs, info = env.reset(seed=0, options={"config": config})
        diff = np.abs(obs["pixels"]["front"].astype(int) - base)
        assert (diff.max(axis=-1) > 10).sum() >= 3, f"{task}: factor {name} left the image unchanged"


def test_same_seeds_give_identical_pixels(make_env):
    config = SceneConfig(
        "pick-place",
        FactorValues(
            table_texture=split_names("texture", "train")[5],
            light=(0.3, 0.7),
            camera_pos=(0.02,) * 7,
            distractors=(SceneObject("proc:torus-001", 0.3, 0.2, 1.0, 0.08, "proc:checker-002"),),
        ),
    )
    actions = np.random.default_rng(0).uniform(-1, 1, (15, 4)).astype(np.float32)
    runs = []
    for _ in range(2):
        env = make_env("pick-place", config, cameras=("front", "top"))
        frames = [env.reset(seed=123)[0]["pixels"]]
        frames += [env.step(a)[0]["pixels"] for a in actions]
        runs.append(frames)
        env.close()
    for a, b in zip(*runs, strict=True):
        for cam in a:
            assert np.array_equal(a[cam], b[cam])
    assert not np.array_equal(runs[0][0]["front"], runs[0][-1]["front"])  # the scene does move


def test_model_holds_the_requested_values(make_env):
    texture = split_names("texture", "eval")[3]
    values = FactorValues(
        object_pos=(0.03, -0.02),
        arm_pos=(0.05, -0.04, 0.02),
        camera_pos=(0.01, -0.02, 0.03, 0.02, -0.01, 0.0, 0.01),
        table_pos=(0.02, -0.03, -0.04),
        object_size=1.2,
        table_texture=texture,
        floor_texture="rgb:0.1,0.6,0.3",
        light=(0.25, 0.7),
        distractors=(SceneObject("proc:box-003", -0.3, 0.15, 0.5, 0.07, "rgb:0.9,0.1,0.1"),),
    )
    env = make_env("pick-place", SceneConfig("pick-place", values))
    _, info = env.reset(seed=0)
    m, d = env.model, env.data
    # lighting
    assert np.allclose(m.vis.headlight.ambient, 0.25) and np.allclose(m.vis.headlight.diffuse, 0.7)
    # table position: the robot side (robot, floor, cameras) moved by the opposite offset
    assert np.allclose(m.body("base").pos, -np.array(values.table_pos))
    assert np.allclose(m.body("tablelink").pos, TABLE_CENTER)
    # camera pose: default + delta (quaternion renormalised), minus the table offset
    cam = CAMERAS["front"]
    quat = cam.quat() + np.array(values.camera_pos[3:])
    assert np.allclose(m.cam("front").pos, np.array(cam.pos) + values.camera_pos[:3] - np.array(values.table_pos))
    assert np.allclose(m.cam("front").quat, quat / np.linalg.norm(quat))
    # textures: the table material now carries exactly the requested image, the floor a flat colour
    rgb = int(mujoco.mjtTextureRole.mjTEXROLE_RGB)
    tex = m.mat_texid[m.material("table_wood").id, rgb]
    adr, size = m.tex_adr[tex], TEXTURE_SIZE * TEXTURE_SIZE * 3
    assert np.array_equal(m.tex_data[adr : adr + size].reshape(TEXTURE_SIZE, TEXTURE_SIZE, 3), load_texture(texture))
    assert m.mat_texid[m.material("basic_floor").id, rgb] == -1
    assert np.allclose(m.mat_rgba[m.material("basic_floor").id][:3], (0.1, 0.6, 0.3))
    # object size: the puck's cylinder is 1.2x larger
    assert np.allclose(m.geom("objGeom").size[:2], np.array([0.02, 0.02]) * 1.2)
    # distractor on the table (table frame -> world)
    assert np.allclose(d.body("fw_distractor0").xpos[:2], TABLE_CENTER[:2] + (-0.3, 0.15))
    # per-episode state: the object started at nominal + offset, the gripper near default + offset
    assert np.allclose(env.metaworld_env.obj_init_pos[:2], np.array([0.0, 0.6]) + values.object_pos)
    assert np.allclose(d.body("hand").xpos, np.array([0.0, 0.6, 0.2]) + values.arm_pos, atol=0.015)
    # and info reports exactly these values
    assert info["factors"]["light"] == [0.25, 0.7] and info["factors"]["object_size"] == 1.2
    assert info["factors"]["table_texture"] == texture


def test_defaults_are_reported_as_the_scene_really_is(make_env):
    env = make_env("door-open")
    _, info = env.reset(seed=5)
    factors = info["factors"]
    assert set(factors) == set(FACTORS)
    assert factors["object_size"] is None and factors["object_shape"] is None  # not applicable
    assert factors["light"] == list(DEFAULT_HEADLIGHT)
    assert np.allclose(env.model.vis.headlight.ambient, DEFAULT_HEADLIGHT[0])
    low, high = factor_range(get_task("door-open"), "object_pos")
    assert all(lo <= v <= hi for v, lo, hi in zip(factors["object_pos"], low, high, strict=True))


def test_missing_asset_file_names_the_path(make_env, tmp_path):
    missing = tmp_path / "gone.png"
    env = make_env("pick-place", SceneConfig("pick-place", FactorValues(table_texture=f"file:{missing}")))
    with pytest.raises((FileNotFoundError, ValueError)) as err:
        env.reset(seed=0)
    assert "gone.png" in str(err.value)
