"""Sampling (protocol/sampling.py) where mutation testing found the suite silent (docs/testing.md): the public
one-factor draw had no in-process test, the seed derivation of ``_aside`` (which every rule-breaking draw uses, so
it decides scenes on every machine) was not pinned, and the distractors' placement was checked only for not
failing: their yaw range, their footprint against each other and the task's keep-out boxes, and the errors named
when the table or the shape pool leaves no room."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from lerobot_factorworld.factors.registry import DISTRACTOR_AREA, DISTRACTOR_SIZE
from lerobot_factorworld.protocol import keepout, sampling
from lerobot_factorworld.protocol.sampling import SamplingOptions, factor_rng, sample_factor, sample_factor_values

TASK = "door-open"


def test_one_factor_drawn_alone_is_the_value_the_grid_draws_from_the_same_stream():
    for name, split in itertools.product(("light", "table_texture", "camera_pos"), ("train", "eval")):
        alone = sample_factor(name, TASK, factor_rng(7, split, name), split)
        (grid,) = sample_factor_values(TASK, [name], n=1, seed=7, split=split)
        assert alone == getattr(grid, name), (name, split)
    # the split's own pool: a held-out (eval) texture is never a training one
    train = {sample_factor("table_texture", TASK, factor_rng(s, "train", "table_texture"), "train") for s in range(30)}
    held_out = {sample_factor("table_texture", TASK, factor_rng(s, "eval", "table_texture"), "eval") for s in range(30)}
    images = lambda names: {n for n in names if not n.startswith("rgb")}  # noqa: E731
    assert images(train) and images(held_out) and not images(train) & images(held_out)


def test_one_factor_follows_its_options_and_the_scene_it_joins():
    colours = [
        sample_factor("table_texture", TASK, np.random.default_rng(s), options=SamplingOptions(rgb_fraction=1.0))
        for s in range(5)
    ]
    assert all(c.startswith("rgb") for c in colours)
    images = [
        sample_factor("table_texture", TASK, np.random.default_rng(s), options=SamplingOptions(rgb_fraction=0.0))
        for s in range(5)
    ]
    assert not any(i.startswith("rgb") for i in images)
    three = sample_factor("distractors", TASK, np.random.default_rng(0), options=SamplingOptions(n_distractors=3))
    assert len(three) == 3 and len(sample_factor("distractors", TASK, np.random.default_rng(0))) == 1  # default: 1
    # the rule against the scene: object texture never equals the table texture it is drawn beside
    for s in range(40):
        table = sample_factor(
            "table_texture", TASK, np.random.default_rng(s), options=SamplingOptions(rgb_fraction=0.0)
        )
        obj = sample_factor("object_texture", TASK, np.random.default_rng(s), options=SamplingOptions(rgb_fraction=0.0), scene={"table_texture": table})  # fmt: skip
        assert obj != table
    with pytest.raises(ValueError, match="unknown split 'val'"):
        sample_factor("light", TASK, np.random.default_rng(0), split="val")


def test_aside_is_seeded_by_the_rng_state_and_leaves_the_rng_where_it_was():
    rng = np.random.default_rng(0)
    before = rng.bit_generator.state
    first = int(sampling._aside(rng).integers(2**62))
    assert rng.bit_generator.state == before  # not advanced
    # pinned: the seed is the first 16 bytes, little-endian, of the SHA-256 of the state's JSON with sorted keys;
    # another derivation changes every rule-breaking draw, hence the scenes, on every machine
    assert first == 2965110437108376986
    assert int(sampling._aside(rng).integers(2**62)) == first  # the same state, the same generator
    rng.random()
    assert int(sampling._aside(rng).integers(2**62)) != first  # another state, another generator


def _distractor_scenes(n: int, count: int) -> list:
    options = SamplingOptions(n_distractors=count)
    return [sample_factor("distractors", TASK, np.random.default_rng(s), options=options) for s in range(n)]


def test_distractors_turn_all_the_way_round_and_keep_clear_of_each_other_and_the_task():
    scenes = _distractor_scenes(150, 5)
    yaws = [d.yaw for scene in scenes for d in scene]
    assert 0 <= min(yaws) < 0.2 and 2 * math.pi - 0.2 < max(yaws) < 2 * math.pi  # [0, 2 pi)
    (xlo, ylo), (xhi, yhi) = DISTRACTOR_AREA
    blocked = [tuple(b) for b in keepout.keepout_boxes(TASK)]
    edge = []
    for scene in scenes:
        boxes = [(d.x - d.size / 2, d.y - d.size / 2, d.x + d.size / 2, d.y + d.size / 2) for d in scene]
        for box, d in zip(boxes, scene):
            assert DISTRACTOR_SIZE[0] <= d.size <= DISTRACTOR_SIZE[1]
            assert xlo <= box[0] and box[2] <= xhi and ylo <= box[1] and box[3] <= yhi  # its whole footprint
            assert not any(sampling._overlap(box, b) for b in blocked)
            edge.append(min(box[0] - xlo, xhi - box[2], box[1] - ylo, yhi - box[3]))
        for a, b in itertools.combinations(boxes, 2):
            assert not sampling._overlap(a, b)
    assert min(edge) < 0.01  # the footprints reach the area's edge: the check above is not vacuous


def test_a_table_with_no_room_and_a_pool_with_no_shape_are_refused_naming_what_ran_out(monkeypatch):
    (xlo, ylo), (xhi, yhi) = DISTRACTOR_AREA
    with monkeypatch.context() as m:
        m.setattr(keepout, "keepout_boxes", lambda task: np.array([[xlo, ylo, xhi, yhi]]))
        with pytest.raises(RuntimeError) as err:
            sample_factor("distractors", TASK, np.random.default_rng(0), options=SamplingOptions(n_distractors=2))
        assert str(err.value) == (
            f"could not place 2 distractors on the free table area of {TASK} after {sampling.MAX_PLACEMENT_TRIES} "
            "tries; use fewer distractors (n_distractors)"
        )
    # every family a look-alike of the task's object: no distractor shape left
    monkeypatch.setattr(sampling, "scene_shape_families", lambda task, own: _every_family())
    with pytest.raises(ValueError, match=r"^no distractor shape in the \w+ pool obeys the rules between factors"):
        sample_factor("distractors", TASK, np.random.default_rng(0))


def _every_family() -> list[str]:
    pool = sampling._Pools("train", SamplingOptions()).shape
    return sorted({pool.family_of(name) for name in pool.names})
