"""Sampling (protocol/sampling.py) where mutation testing found the suite silent (docs/testing.md): the public
one-factor draw had no in-process test, the seed derivation of ``_aside`` (which every rule-breaking draw uses, so
it decides scenes on every machine) was not pinned, and the distractors' placement was checked only for not
failing: their yaw range, their footprint against each other and the task's keep-out boxes, and the errors named
when the table or the shape pool leaves no room. Nor did an in-process test hold the options' bounds (rgb_fraction
in [0, 1], 0 to 5 distractors) and their messages, the width a continuous draw reads, the defaults (training split,
seed 0), what a configuration records (split, id, the family's content, a task row taken like its name), a shift's
id, the exact edge of the colour-or-image draw, or the errors naming the pool where an object shape or a texture
has no allowed name left."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from lerobot_factorworld.factors.registry import DISTRACTOR_AREA, DISTRACTOR_SIZE, SceneObject
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


def test_aside_reads_the_whole_state_of_any_bit_generator_a_caller_passes():
    # sample_factor takes any np.random.Generator; only PCG64 (default_rng's) has an all-integer state. MT19937's
    # key, Philox's counter/key/buffer and SFC64's state are uint32/uint64 arrays, which the JSON encoder can only
    # write through ``default`` (as lists): without it _aside raises, and with a ``default`` that drops them the
    # arrays become ``null``, so every state at the same position would seed the same aside generator
    for make in (np.random.MT19937, np.random.Philox, np.random.SFC64):
        rng_a, rng_b = np.random.Generator(make(1)), np.random.Generator(make(2))
        assert type(rng_a.bit_generator.state["state"]) is dict  # the arrays sit in this nested dict
        before = rng_a.bit_generator.state["state"]
        draw_a = int(sampling._aside(rng_a).integers(2**62))
        assert all(np.array_equal(v, rng_a.bit_generator.state["state"][k]) for k, v in before.items())  # unmoved
        assert int(sampling._aside(rng_a).integers(2**62)) == draw_a  # the same state, the same generator
        # seeds 1 and 2 give the same position and other arrays: the arrays alone tell the two states apart
        assert int(sampling._aside(rng_b).integers(2**62)) != draw_a, make.__name__
    # through the public draw: a table texture forced to break its rule (the object wears the very texture the
    # unconstrained draw picks) is replaced through _aside, with an MT19937 generator as with PCG64
    images = SamplingOptions(rgb_fraction=0.0)
    for seed in range(3):
        free = sample_factor("table_texture", TASK, np.random.Generator(np.random.MT19937(seed)), options=images)
        rng = np.random.Generator(np.random.MT19937(seed))
        table = sample_factor("table_texture", TASK, rng, options=images, scene={"object_texture": free})
        assert table != free and table in sampling._Pools("train", images).texture.names


def _two_shape_families(folder: Path) -> SamplingOptions:
    """A shape folder of two families, crab/ and moth/, of six meshes each (sampling only lists the files, so a
    one-vertex .obj is enough), split by variant so that both families have files on each side."""
    for family in ("crab", "moth"):
        (folder / family).mkdir()
        for i in range(1, 7):
            (folder / family / f"{family}_{i}.obj").write_text("v 0 0 0\n")
    return SamplingOptions(shape_folder=str(folder), asset_split="variant", n_distractors=2)


def _folder_family(name: str) -> str:
    """The family a ``file:`` name of that folder belongs to: its subfolder."""
    return Path(name.removeprefix("file:")).parent.name


def test_a_shape_folder_family_is_its_top_level_subfolder_for_the_look_alike_rule(tmp_path):
    options = _two_shape_families(tmp_path)
    pool = sampling._Pools("train", options).shape
    moths = [n for n in pool.names if "/moth/" in n]
    assert len(moths) >= 2 and len(moths) < len(pool.names)
    assert pool.family_of(moths[0]) == "moth"  # the subfolder, not the file (asset_family without the folder)

    def families(scene):
        return [
            _folder_family(d.shape)
            for s in range(20)
            for d in sample_factor("distractors", "pick-place", np.random.default_rng(s), options=options, scene=scene)
        ]

    # no folder family is shown by pick-place's own scene: both are drawn (40 draws, about 4 in 7 of them moths)
    assert set(families({})) == {"crab", "moth"}
    # beside a moth object every other moth file is a look-alike: all 40 distractors are crabs
    assert families({"object_shape": moths[0]}) == ["crab"] * 40


# (x0, y0, x1, y1) boxes: open rectangles overlap iff both their x and their y intervals overlap
UNIT = (0.0, 0.0, 1.0, 1.0)
OVERLAP_CASES = [
    (UNIT, (0.5, 0.5, 2.0, 2.0), True),  # corner over corner
    (UNIT, UNIT, True),  # the same box
    (UNIT, (1.0, 0.0, 2.0, 1.0), False),  # touching at x = 1 from the right: no area in common
    ((1.0, 0.0, 2.0, 1.0), UNIT, False),  # the same, the other way round
    (UNIT, (0.0, 1.0, 1.0, 2.0), False),  # touching at y = 1 from above
    ((0.0, 1.0, 1.0, 2.0), UNIT, False),  # the same, the other way round
    ((5.0, 0.0, 6.0, 1.0), UNIT, False),  # far right, low y: only a's x0 (5) > b's x1 (1) separates them
    ((5.0, 0.0, 6.0, 1.0), (0.0, 0.0, 1.0, 10.0), False),  # far right of a tall box (b's y1 = 10 > a's x0)
    (UNIT, (5.0, 0.0, 6.0, 1.0), False),  # far left: only b's x0 (5) > a's x1 (1) separates them
    ((0.0, 0.0, 1.0, 10.0), (5.0, 0.0, 6.0, 1.0), False),  # a tall box far left of b (a's y1 = 10 > b's x0)
    ((0.0, 5.0, 1.0, 6.0), (0.0, 0.0, 1.0, 2.0), False),  # high above: only a's y0 (5) > b's y1 (2) separates
]


@pytest.mark.parametrize(("a", "b", "expected"), OVERLAP_CASES)
def test_boxes_overlap_only_where_they_share_area(a, b, expected):
    assert sampling._overlap(a, b) is expected


def test_boxes_overlap_exactly_when_both_intervals_overlap_on_a_grid():
    # every pair of boxes with corners on a 4 x 4 grid (touching edges included) against the interval rule
    corners = [(x0, y0, x1, y1) for x0, x1 in itertools.combinations(range(4), 2) for y0, y1 in itertools.combinations(range(4), 2)]  # fmt: skip
    for a, b in itertools.product(corners, repeat=2):
        expected = max(a[0], b[0]) < min(a[2], b[2]) and max(a[1], b[1]) < min(a[3], b[3])
        assert sampling._overlap(a, b) == expected, (a, b)


def test_a_distractor_shifted_to_held_out_files_avoids_the_family_of_an_object_inherited_from_training(tmp_path):
    # the look-alike rule across splits: an object shape drawn from the training side of a shape folder keeps
    # its family (its top-level subfolder) when a shift draws distractors from the held-out side. Before the
    # pool knew its folder, the inherited object's family was its own file name and 17 of 30 shifted
    # environments held a distractor of the object's family
    options = _two_shape_families(tmp_path)
    base = sampling.sample_configs("pick-place", 5, seed=0, factors=["object_shape"], options=options)
    objects = {_folder_family(c.factors.object_shape) for c in base}
    assert objects <= {"crab", "moth"} and objects  # the objects come from the folder
    for split in ("train", "eval"):
        shifted = sampling.shift_configs(base, "distractors", 30, split=split, options=options)
        for config in shifted:
            object_family = _folder_family(config.factors.object_shape)
            shown = {_folder_family(d.shape) for d in config.factors.distractors}
            assert object_family not in shown, (split, config.factors.object_shape, shown)


def test_options_accept_their_documented_bounds_and_refuse_beyond_them_naming_the_range():
    # rgb_fraction is a probability: both ends are valid, 1.5 and -0.1 are not
    assert [SamplingOptions(rgb_fraction=p).rgb_fraction for p in (0.0, 1.0)] == [0.0, 1.0]
    for bad in (1.5, -0.1):
        with pytest.raises(ValueError, match=rf"^rgb_fraction must be in \[0, 1\], got {bad}$"):
            SamplingOptions(rgb_fraction=bad)
    # no distractor at all is a valid study (the object alone on the table): every environment gets an empty tuple
    none = SamplingOptions(n_distractors=0)
    assert sample_factor("distractors", TASK, np.random.default_rng(3), options=none) == ()
    configs = sampling.sample_configs(TASK, 3, seed=2, factors=["distractors", "light"], options=none)
    assert [c.factors.distractors for c in configs] == [(), (), ()]
    assert SamplingOptions(n_distractors=5).n_distractors == 5  # MAX_DISTRACTORS itself is valid
    for bad in (-1, 6):
        with pytest.raises(ValueError, match=rf"^n_distractors must be in \[0, 5\], got {bad}$"):
            SamplingOptions(n_distractors=bad)


def test_a_continuous_factor_is_drawn_from_the_width_the_options_name():
    # door-open's camera_pos has no task limit: narrow (the default) is +-0.025 per component, wide +-0.075, so a
    # draw is low + (high - low) * u with the stream's next seven uniforms u
    u = np.random.default_rng(11).random(7)
    default = sample_factor("camera_pos", TASK, np.random.default_rng(11))
    wide = sample_factor("camera_pos", TASK, np.random.default_rng(11), options=SamplingOptions(widths={"camera_pos": "wide"}))  # fmt: skip
    assert default == pytest.approx(tuple(-0.025 + 0.05 * u), rel=1e-12, abs=1e-15)
    assert wide == pytest.approx(tuple(-0.075 + 0.15 * u), rel=1e-12, abs=1e-15)
    # the width of one factor leaves the others at theirs: light keeps its only ("paper") range [0.2, 0.8]^2
    options = SamplingOptions(widths={"camera_pos": "medium"})
    (grid,) = sample_factor_values(TASK, ["camera_pos", "light"], n=1, seed=4, options=options)
    u_cam, u_light = factor_rng(4, "train", "camera_pos").random(7), factor_rng(4, "train", "light").random(2)
    assert grid.camera_pos == pytest.approx(tuple(-0.05 + 0.1 * u_cam), rel=1e-12, abs=1e-15)
    assert grid.light == pytest.approx(tuple(0.2 + 0.6 * u_light), rel=1e-12, abs=1e-15)


def _one_shape_per_family() -> tuple:
    pool = sampling._Pools("train", SamplingOptions()).shape
    first = {pool.family_of(name): name for name in reversed(pool.names)}  # the family's first name
    return tuple(SceneObject(shape=first[f], x=0.0, y=0.0, yaw=0.0, size=0.1, texture="proc:camo-010") for f in sorted(first))  # fmt: skip


def test_an_object_shape_with_every_family_taken_by_a_distractor_is_refused_naming_the_shape_pool():
    distractors = _one_shape_per_family()
    pool = sampling._Pools("train", SamplingOptions()).shape
    # one family left free: every draw (a rule-breaking one is replaced) lands in it
    free = pool.family_of(distractors[0].shape)
    shapes = [
        sample_factor("object_shape", "pick-place", np.random.default_rng(s), scene={"distractors": distractors[1:]})
        for s in range(6)
    ]
    assert {pool.family_of(s) for s in shapes} == {free} and len(set(shapes)) > 1
    with pytest.raises(ValueError, match=r"^no object shape in the shape pool obeys the rules between factors \(all excluded\)$"):  # fmt: skip
        sample_factor("object_shape", "pick-place", np.random.default_rng(0), scene={"distractors": distractors})


def test_a_texture_pool_with_no_allowed_image_is_refused_naming_the_texture_pool(tmp_path):
    # two families of one image each: the family split gives the training side wood/ alone (brick/ is held out)
    for family in ("brick", "wood"):
        (tmp_path / family).mkdir()
        (tmp_path / family / f"{family}.png").write_bytes(b"")  # sampling only lists the files
    options = SamplingOptions(texture_folder=str(tmp_path), rgb_fraction=0.0)
    (wood,) = sampling._Pools("train", options).texture.names
    assert wood.endswith("/wood/wood.png")
    assert sample_factor("object_texture", TASK, np.random.default_rng(0), options=options) == wood
    # beside a wood table the object has no image left
    with pytest.raises(ValueError, match=r"^no texture in the texture pool obeys the rules between factors \(all excluded\)$"):  # fmt: skip
        sample_factor("object_texture", TASK, np.random.default_rng(0), options=options, scene={"table_texture": wood})
    # ... but a draw that asks for a colour needs no image: every colour draw beside the wood table is a colour
    colours = SamplingOptions(texture_folder=str(tmp_path), rgb_fraction=1.0)
    drawn = [
        sample_factor("object_texture", TASK, np.random.default_rng(s), options=colours, scene={"table_texture": wood})
        for s in range(5)
    ]
    assert all(t.startswith("rgb:") for t in drawn) and len(set(drawn)) == 5


# PCG64 steps its 128-bit state (state * MULTIPLIER + inc mod 2**128), then outputs the xor of the new state's
# halves rotated right by its top 6 bits; random() is that output's top 53 bits times 2**-53
PCG64_MULTIPLIER = 0x2360ED051FC65DA44385DF649FCCF645


def _rng_whose_next_random_is(u: float) -> np.random.Generator:
    """A PCG64 generator whose next ``random()`` is exactly ``u`` (a multiple of 2**-53): its stepped state is
    ``k << 11`` (high half 0, so no rotation and the output is the low half, ``k << 11``), for ``u = k * 2**-53``."""
    k, inc = int(u * 2**53), (1 << 100) + 1  # inc: any odd number
    assert k * 2.0**-53 == u
    before = ((k << 11) - inc) * pow(PCG64_MULTIPLIER, -1, 2**128) % 2**128
    rng = np.random.Generator(np.random.PCG64())
    rng.bit_generator.state = {"bit_generator": "PCG64", "state": {"state": before, "inc": inc}, "has_uint32": 0, "uinteger": 0}  # fmt: skip
    return rng


def test_a_texture_is_a_colour_exactly_when_its_uniform_draw_is_below_rgb_fraction():
    assert _rng_whose_next_random_is(0.5).random() == 0.5 and _rng_whose_next_random_is(0.0).random() == 0.0
    # P(u < p) = p for u uniform on the 2**-53 grid of [0, 1): u == p gives an image, the grid point below a colour;
    # so rgb_fraction 0 ("images only") never gives a colour, not even for a draw of exactly 0
    for p in (0.0, 0.25, 0.5):
        options = SamplingOptions(rgb_fraction=p)
        at_p = sample_factor("table_texture", TASK, _rng_whose_next_random_is(p), options=options)
        assert not at_p.startswith("rgb:"), (p, at_p)
        if p > 0:
            below = sample_factor("table_texture", TASK, _rng_whose_next_random_is(p - 2**-53), options=options)
            assert below.startswith("rgb:"), (p, below)


def test_sampling_defaults_are_the_training_split_and_seed_0():
    factors = ["light", "table_texture"]
    train = sample_factor_values(TASK, factors, n=3, seed=5, split="train")
    assert sample_factor_values(TASK, factors, n=3, seed=5) == train
    assert sample_factor_values(TASK, factors, n=3, seed=5, split="eval") != train
    seed0 = sampling.sample_configs(TASK, 3, seed=0, factors=factors)
    assert sampling.sample_configs(TASK, 3, factors=factors) == seed0
    assert sampling.sample_configs(TASK, 3, seed=1, factors=factors) != seed0
    shifted = sampling.shift_configs(seed0, "light", 4, seed=0)
    assert sampling.shift_configs(seed0, "light", 4) == shifted
    assert sampling.shift_configs(seed0, "light", 4, seed=1) != shifted


def test_configs_record_their_task_split_id_and_the_familys_content(monkeypatch):
    from lerobot_factorworld.families import family_of
    from lerobot_factorworld.pick.sampling import sample_layouts
    from lerobot_factorworld.tasks import get_task

    options = SamplingOptions(n_objects=3)
    configs = sampling.sample_configs("pick", 3, seed=4, split="eval", factors=["light"], options=options)
    assert [c.env_id for c in configs] == ["pick/eval/000", "pick/eval/001", "pick/eval/002"]
    assert [c.split for c in configs] == ["eval"] * 3  # not SceneConfig's default, "train"
    # the content is the family's layouts from their own stream (seed 4, eval, 3 objects), one per environment
    assert [c.content for c in configs] == sample_layouts(3, 4, "eval", 3)
    assert len({c.content for c in configs}) == 3 and all(len(c.content.objects) == 3 for c in configs)
    # a task row works as its name does, and the family's hook is handed that row (a family may read it)
    seen = []
    family = family_of("pick")
    real = family.sample_contents
    monkeypatch.setattr(family, "sample_contents", lambda task, *rest: seen.append(task) or real(task, *rest))
    row = get_task("pick")
    assert sampling.sample_configs(row, 3, seed=4, split="eval", factors=["light"], options=options) == configs
    assert seen == [row]
    with pytest.raises(ValueError, match=r"^the number of environments must be at least 1, got 0$"):
        sampling.sample_configs(TASK, 0)


def test_shifted_configs_are_named_by_the_shifted_factors_and_refuse_an_empty_base():
    base = sampling.sample_configs(TASK, 2, seed=3, factors=["light"])
    assert [c.env_id for c in base] == ["door-open/train/000", "door-open/train/001"]
    pair = sampling.shift_configs(base, ("light", "camera_pos"), 3)
    assert [c.env_id for c in pair] == [f"door-open/shift-light+camera_pos/00{j}" for j in range(3)]
    assert [c.split for c in pair] == ["eval"] * 3
    one = sampling.shift_configs(base, "table_texture", 2, split="train")
    assert [c.env_id for c in one] == ["door-open/shift-table_texture/000", "door-open/shift-table_texture/001"]
    with pytest.raises(ValueError, match=r"^shift_configs needs at least one base configuration$"):
        sampling.shift_configs([], "light", 2)


def test_shifted_configs_refuse_no_factor_no_environment_and_a_base_of_two_tasks():
    base = sampling.sample_configs(TASK, 2, seed=3, factors=["light"])
    with pytest.raises(ValueError, match=r"^shift_configs needs at least one factor to shift$"):
        sampling.shift_configs(base, (), 2)
    with pytest.raises(ValueError, match=r"^the number of environments must be at least 1, got 0$"):
        sampling.shift_configs(base, "light", 0)
    # a pick-place environment must not come out named door-open/... with door-open's ranges
    mixed = [*base, *sampling.sample_configs("pick-place", 1, seed=3, factors=["light"])]
    with pytest.raises(ValueError, match=r"^shift_configs needs base configurations of one task, got \['door-open', 'pick-place'\]$"):  # fmt: skip
        sampling.shift_configs(mixed, "object_pos", 2)
