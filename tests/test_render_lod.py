"""The ``lod`` render quality: simplified robot meshes, identical physics, close pixels, simplified once."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from lerobot_factorworld.experts import expert_policy, rollout
from lerobot_factorworld.factors.values import FactorValues
from lerobot_factorworld.scene import lod
from lerobot_factorworld.scene.build import QUALITIES, build_model, build_spec, check_quality
from lerobot_factorworld.tasks import TASKS


def _drawn_triangles(model: mujoco.MjModel) -> int:
    return sum(
        int(model.mesh_facenum[model.geom_dataid[g]])
        for g in range(model.ngeom)
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH and model.geom_group[g] < lod.HIDDEN_GROUP
    )


def _colliding(model: mujoco.MjModel) -> list[int]:
    return [g for g in range(model.ngeom) if model.geom_contype[g] or model.geom_conaffinity[g]]


@pytest.mark.parametrize("task", sorted(TASKS))
def test_lod_compiles_with_the_same_physics_and_fewer_triangles(task):
    fast = build_model(task, FactorValues(), quality="fast")
    low = build_model(task, FactorValues(), quality="lod")
    assert (low.nq, low.nv, low.nbody, low.njnt, low.nu) == (fast.nq, fast.nv, fast.nbody, fast.njnt, fast.nu)
    for field in ("body_mass", "body_inertia", "body_ipos", "body_iquat", "qpos0", "opt.timestep"):
        obj_fast, obj_low = fast, low
        for part in field.split("."):
            obj_fast, obj_low = getattr(obj_fast, part), getattr(obj_low, part)
        np.testing.assert_array_equal(obj_low, obj_fast, err_msg=field)
    col_fast, col_low = _colliding(fast), _colliding(low)
    assert [fast.geom(g).name for g in col_fast] == [low.geom(g).name for g in col_low]
    for field in ("geom_size", "geom_pos", "geom_quat", "geom_friction", "geom_contype", "geom_conaffinity"):
        np.testing.assert_array_equal(getattr(low, field)[col_low], getattr(fast, field)[col_fast], err_msg=field)
    assert _drawn_triangles(low) < 0.5 * _drawn_triangles(fast)


@pytest.mark.parametrize("task", ["door-open", "pick-place"])
def test_lod_trajectories_are_bit_identical(make_env, task):
    trajectories = []
    for quality in ("fast", "lod"):
        env = make_env(task, cameras=(), quality=quality)
        qpos: list[np.ndarray] = []
        rollout(
            env,
            expert_policy(task),
            seed=2,
            noise_std=0.1,
            max_steps=40,
            after_step=lambda e, q=qpos: q.append(e.data.qpos.copy()),
        )
        trajectories.append(np.array(qpos))
    assert len(trajectories[0]) == 40
    assert np.array_equal(trajectories[0], trajectories[1])


def test_lod_pixels_are_close(make_env):
    frames = []
    for quality in ("fast", "lod"):
        obs, _ = make_env("door-open", image_size=84, quality=quality).reset(seed=0)
        frames.append(obs["pixels"]["front"].astype(np.int16))
    diff = np.abs(frames[0] - frames[1])
    assert 0.0 < diff.mean() < 2.0  # levels of 255 (measured: under 1)
    assert (diff.max(axis=-1) > 16).mean() < 0.05


def test_meshes_are_simplified_once_then_read_from_the_caches(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(lod, "_simplified", {})
    monkeypatch.setattr(lod, "stats", dict.fromkeys(lod.stats, 0))
    assert lod.cache_dir() == tmp_path / "lerobot_factorworld" / "lod"

    first = build_spec("door-open", FactorValues(), quality="lod")
    assert lod.stats == {"simplified": len(lod.LOD_MESHES), "disk_hits": 0, "memory_hits": 0}
    assert len(list(lod.cache_dir().glob("*.npz"))) == len(lod.LOD_MESHES)

    build_spec("pick-place", FactorValues(), quality="lod")  # same process: from memory
    assert lod.stats["simplified"] == len(lod.LOD_MESHES)
    assert lod.stats["memory_hits"] == len(lod.LOD_MESHES)

    lod.clear_memory_cache()  # as a new process: from disk, never simplified again
    second = build_spec("door-open", FactorValues(), quality="lod")
    assert lod.stats["simplified"] == len(lod.LOD_MESHES)
    assert lod.stats["disk_hits"] == len(lod.LOD_MESHES)
    assert np.array_equal(first.mesh("l0").uservert, second.mesh("l0").uservert)
    assert np.array_equal(first.compile().mesh_vert, second.compile().mesh_vert)


def test_other_qualities_do_not_touch_the_robot_meshes(monkeypatch):
    monkeypatch.setattr(lod, "stats", dict.fromkeys(lod.stats, 0))
    for quality in ("fast", "full"):
        spec = build_spec("door-open", FactorValues(), quality=quality)
        assert spec.mesh("l0").file.endswith("l0.stl")
    assert sum(lod.stats.values()) == 0


def test_bad_quality_names_are_rejected_naming_the_valid_ones(make_env):
    assert QUALITIES == ("fast", "full", "lod")
    for call in (
        lambda: check_quality("ultra"),
        lambda: build_spec("door-open", FactorValues(), quality="ultra"),
        lambda: make_env("door-open", quality="ultra"),
    ):
        with pytest.raises(ValueError, match="'ultra'; valid: fast, full, lod"):
            call()
    check_quality("lod")
