"""The dataset's schema (datasets/schema.py) where mutation testing found the suite silent (docs/testing.md): the
frame features' keys, types and shapes, every factor column written with a real, non-default value and read back
with its type, the empty value of each kind of column (a factor that does not apply), and the episode's
instruction, target and objects columns of a pick task, of a task without them and of an old dataset."""

from __future__ import annotations

import json
import math

from lerobot_factorworld.datasets import schema
from lerobot_factorworld.factors.values import SceneObject

FACTORS = {
    "object_pos": (0.125, 0.75, 0.0),
    "arm_pos": (-0.25, 0.5, 0.375),
    "camera_pos": (1.5, -0.5, 0.75),
    "table_pos": (0.0625, -0.125, 0.0),
    "object_size": 1.25,
    "object_shape": "cylinder",
    "object_texture": "wood_3",
    "table_texture": "marble_1",
    "floor_texture": "tiles_7",
    "light": (0.5, 0.25, 0.125),
    "distractors": (
        SceneObject("box", 0.1, -0.2, 0.5, 0.04, "metal_2"),
        SceneObject("sphere", -0.3, 0.05, 0.0, 0.03, "plastic_1", name="ball"),
    ),
}
DISTRACTORS = [
    {"name": "", "shape": "box", "size": 0.04, "texture": "metal_2", "x": 0.1, "y": -0.2, "yaw": 0.5},
    {"name": "ball", "shape": "sphere", "size": 0.03, "texture": "plastic_1", "x": -0.3, "y": 0.05, "yaw": 0.0},
]


def test_the_frame_features():
    assert schema.frame_features(("front", "wrist"), (48, 64), use_videos=False) == {
        "observation.images.front": {"dtype": "image", "shape": (48, 64, 3), "names": ["height", "width", "channels"]},
        "observation.images.wrist": {"dtype": "image", "shape": (48, 64, 3), "names": ["height", "width", "channels"]},
        "observation.state": {
            "dtype": "float32",
            "shape": (8,),
            "names": ["x", "y", "z", "gripper", "prev_x", "prev_y", "prev_z", "prev_gripper"],
        },
        "action": {"dtype": "float32", "shape": (4,), "names": ["dx", "dy", "dz", "grip"]},
    }
    assert schema.frame_features(("top",), (32, 16))["observation.images.top"]["dtype"] == "video"


def test_every_factor_column_round_trips_its_value_and_type():
    columns = schema.encode_factors(FACTORS)
    assert columns == {
        "factors/object_pos": [0.125, 0.75, 0.0],
        "factors/arm_pos": [-0.25, 0.5, 0.375],
        "factors/camera_pos": [1.5, -0.5, 0.75],
        "factors/table_pos": [0.0625, -0.125, 0.0],
        "factors/object_size": 1.25,
        "factors/object_shape": "cylinder",
        "factors/object_texture": "wood_3",
        "factors/table_texture": "marble_1",
        "factors/floor_texture": "tiles_7",
        "factors/light": [0.5, 0.25, 0.125],
        "factors/distractors": json.dumps(DISTRACTORS, sort_keys=True),
    }
    assert all(type(v) is float for v in columns["factors/arm_pos"]) and type(columns["factors/object_size"]) is float
    decoded = schema.decode_factors(columns)
    assert decoded == FACTORS
    assert all(type(v) is float for v in decoded["camera_pos"]) and type(decoded["object_size"]) is float
    # integers and a dict for a distractor are written as floats and as the same JSON object
    ints = schema.encode_factors({"object_size": 2, "light": (1, 0, 1), "distractors": [DISTRACTORS[1]]})
    assert ints["factors/object_size"] == 2.0 and type(ints["factors/object_size"]) is float
    assert ints["factors/light"] == [1.0, 0.0, 1.0] and all(type(v) is float for v in ints["factors/light"])
    assert ints["factors/distractors"] == json.dumps([DISTRACTORS[1]], sort_keys=True)


def test_a_factor_that_does_not_apply_has_its_kinds_empty_value():
    columns = schema.encode_factors({"light": (0.5, 0.5, 0.5)})
    assert columns["factors/object_pos"] == [] and columns["factors/object_shape"] == ""
    assert math.isnan(columns["factors/object_size"]) and columns["factors/distractors"] == "[]"
    decoded = schema.decode_factors(columns)
    assert decoded == {**{name: None for name in FACTORS}, "light": (0.5, 0.5, 0.5), "distractors": ()}
    assert schema.decode_factors({**columns, "factors/object_size": None})["object_size"] is None


def test_the_episode_columns_of_a_pick_task_a_task_without_them_and_an_old_dataset():
    objects = [{"yaw": 1.0, "x": 0.1, "y": 0.2, "name": "mug"}, {"name": "apple", "x": -0.1, "y": 0.0, "yaw": 0.0}]
    info = {"pick": {"target": "mug", "objects": objects}}
    columns = schema.encode_episode(info, "pick up the mug", "pick")
    assert columns == {
        "factorworld/instruction": "pick up the mug",
        "factorworld/target": "mug",
        "factorworld/objects": '[{"name": "mug", "x": 0.1, "y": 0.2, "yaw": 1.0}, '
        '{"name": "apple", "x": -0.1, "y": 0.0, "yaw": 0.0}]',  # keys sorted: one text per set of objects
    }
    assert schema.decode_episode(columns) == {"instruction": "pick up the mug", "target": "mug", "objects": objects}
    # a task without content: its info's "pick" entry is not its own
    assert schema.encode_episode(info, "open the door", "pick-place") == {
        "factorworld/instruction": "open the door",
        "factorworld/target": "",
        "factorworld/objects": "[]",
    }
    assert schema.encode_episode({}, "pick", "pick") == {
        "factorworld/instruction": "pick",
        "factorworld/target": "",
        "factorworld/objects": "[]",
    }
    empty = schema.decode_episode(schema.encode_episode({}, "go", "pick-place"))
    assert empty == {"instruction": "go", "target": None, "objects": []}
    assert schema.decode_episode({}) == {"instruction": None, "target": None, "objects": []}
