"""Asset pools, splits, determinism and MuJoCo-compatibility of lerobot_factorworld.assets."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest
from PIL import Image

from lerobot_factorworld import assets as A
from lerobot_factorworld.assets import library, split_document
from lerobot_factorworld.assets.mesh import face_areas, is_watertight, signed_volume

REPO = Path(__file__).resolve().parents[1]


# ----------------------------------------------------------------------------------------------------------
# pools and splits


@pytest.mark.parametrize("mode", ["family", "variant"])
@pytest.mark.parametrize(("kind", "min_train", "min_eval"), [("texture", 81, 81), ("shape", 100, 70)])
def test_builtin_splits_disjoint_complete_and_large(kind: str, min_train: int, min_eval: int, mode: str) -> None:
    assert library.PAPER_SPLIT_SIZES[kind] == {"train": min_train, "eval": min_eval}  # what the script enforces
    train, evals = A.split_names(kind, "train", mode=mode), A.split_names(kind, "eval", mode=mode)
    assert len(train) >= min_train and len(evals) >= min_eval  # the paper: 81/81 textures, 100/70 objects
    assert not set(train) & set(evals)
    assert len(set(train)) == len(train) and len(set(evals)) == len(evals)
    assert sorted(train + evals) == sorted(A.builtin_names(kind))
    assert list(train) == sorted(train)


@pytest.mark.parametrize("kind", ["texture", "shape"])
def test_family_split_holds_whole_families_out(kind: str) -> None:
    train, evals = A.split_names(kind, "train"), A.split_names(kind, "eval")
    assert (train, evals) == (A.split_names(kind, "train", mode="family"), A.split_names(kind, "eval", mode="family"))
    train_fams, eval_fams = {A.asset_family(n) for n in train}, {A.asset_family(n) for n in evals}
    assert not train_fams & eval_fams  # no family on both sides, Meta-World files included
    assert train_fams | eval_fams == set(A.builtin_families(kind))
    assert len(eval_fams) >= 5  # held out: several whole kinds, not a handful of variants
    stored = json.loads(library.SPLITS_FILE.read_text(encoding="utf-8"))["splits"]["family"][kind]["families"]
    assert (sorted(train_fams), sorted(eval_fams)) == (stored["train"], stored["eval"])
    assert set(A.seen_families(kind)) <= train_fams  # what the default scenes show is never held out
    # the per-variant split is what the family split fixes: most families sit on both of its sides
    shared = {A.asset_family(n) for n in A.split_names(kind, "train", mode="variant")} & {
        A.asset_family(n) for n in A.split_names(kind, "eval", mode="variant")
    }
    assert len(shared) > len(A.builtin_families(kind)) // 2


def test_families_of_builtin_assets() -> None:
    assert A.DEFAULT_ASSET_SPLIT == "family" and A.ASSET_SPLITS == ("family", "variant")
    assert not set(A.builtin_families("texture")) & set(A.builtin_families("shape"))
    assert A.asset_family("proc:marble-003") == "marble"
    assert A.asset_family("metaworld:textures/wood2.png") == "wood"  # Meta-World's woods are one family
    assert A.asset_family("metaworld:objects/meshes/puck/puck.stl") == "cylinder"
    assert A.asset_family("file:/somewhere/x.png") == "file:/somewhere/x.png"  # outside any folder: its own
    assert A.seen_families("texture") == ("bricks", "grid", "plain", "wood") and A.seen_families("shape") == (
        "box",
        "cylinder",
        "ellipsoid",
    )
    assert A.asset_families("shape")["proc:mug-004"] == "mug"


def test_default_scene_textures_are_metaworlds() -> None:
    """DEFAULT_TABLE/FLOOR_TEXTURE restate Meta-World's scene; check them against its XML."""
    for scene in sorted((A.metaworld_assets_dir() / "scene").glob("basic_scene*.xml")):
        text = scene.read_text(encoding="utf-8")
        for tex, default in (("T_table", A.DEFAULT_TABLE_TEXTURE), ("T_floor", A.DEFAULT_FLOOR_TEXTURE)):
            expected = f'name="{tex}"'
            line = next(line for line in text.splitlines() if expected in line)
            assert f'file="../{default.removeprefix("metaworld:")}"' in line, (scene.name, line)


def test_splits_file_matches_code_and_script_is_deterministic() -> None:
    doc = json.loads(library.SPLITS_FILE.read_text(encoding="utf-8"))
    assert doc == split_document.builtin_splits_document(), "run: python scripts/make_asset_splits.py"
    assert set(doc["splits"]) == {"family", "variant"}
    out = subprocess.run(
        [sys.executable, str(REPO / "scripts" / "make_asset_splits.py"), "--check"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "family  texture  train=" in out.stdout and "variant shape" in out.stdout


def test_script_refuses_splits_smaller_than_the_papers(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_asset_splits", REPO / "scripts" / "make_asset_splits.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    monkeypatch.setattr(
        script, "PAPER_SPLIT_SIZES", {"texture": {"train": 81, "eval": 200}, "shape": {"train": 1, "eval": 1}}
    )
    monkeypatch.setattr(sys, "argv", ["make_asset_splits.py", "--check"])
    assert script.main() == 1
    err = capsys.readouterr().err
    assert "smaller than the paper's pools: family texture eval: " in err and "variant texture eval: " in err
    assert "texture train" not in err and "shape" not in err


@pytest.mark.parametrize("mode", ["family", "variant"])
def test_hand_edited_splits_file_is_rejected(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, mode: str) -> None:
    doc = json.loads(library.SPLITS_FILE.read_text(encoding="utf-8"))
    lists = doc["splits"][mode]["texture"]["names"]
    lists["train"].append(lists["eval"].pop())  # sneak an eval texture into train
    edited = tmp_path / "asset_splits.json"
    edited.write_text(json.dumps(doc), encoding="utf-8")
    monkeypatch.setattr(library, "SPLITS_FILE", edited)
    library._builtin_splits.cache_clear()
    try:
        with pytest.raises(A.AssetSplitsError, match="make_asset_splits"):
            A.split_names("texture", "train")
    finally:
        library._builtin_splits.cache_clear()


def _move_to_train(lists: dict) -> None:
    """Move one eval name of a multi-variant family to train, listing its family on both sides."""
    name = next(n for n in lists["names"]["eval"] if n.startswith("proc:"))
    lists["names"]["eval"].remove(name)
    lists["names"]["train"] = sorted([*lists["names"]["train"], name])
    lists["families"]["train"] = sorted({*lists["families"]["train"], A.asset_family(name)})


@pytest.mark.parametrize(
    ("mode", "edit", "message"),
    [
        ("variant", lambda d: d["names"]["train"].append(d["names"]["eval"][0]), "train and eval overlap"),
        ("family", lambda d: d["names"]["eval"].pop(), "its names are not the built-in pool"),
        ("variant", lambda d: d["families"]["eval"].pop(), "its eval families are not the families of its eval"),
        ("family", _move_to_train, "a family is on both sides of the family split"),
    ],
    ids=["overlap", "not-the-pool", "families-of-names", "family-on-both-sides"],
)
def test_splits_file_checks_hold_even_with_a_matching_sha256(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, mode: str, edit, message: str
) -> None:
    """Lists edited and re-hashed (as a script bug could write them) still fail the file's own checks."""
    doc = json.loads(library.SPLITS_FILE.read_text(encoding="utf-8"))
    edit(doc["splits"][mode]["shape"])
    doc["sha256"] = library.splits_digest(doc["splits"])
    edited = tmp_path / "asset_splits.json"
    edited.write_text(json.dumps(doc), encoding="utf-8")
    monkeypatch.setattr(library, "SPLITS_FILE", edited)
    library._builtin_splits.cache_clear()
    try:
        with pytest.raises(A.AssetSplitsError, match=f"{mode} split of shapes: {message}.*make_asset_splits"):
            A.split_names("texture", "train")
    finally:
        library._builtin_splits.cache_clear()


def _shown_in_compiled_scene(task: str) -> tuple[set[str], set[str], set[str]]:
    """(textures, pool meshes, object textures) on visible geoms, read from the compiled model: an
    independent check of :func:`scene_assets`, which reads the uncompiled spec."""
    from lerobot_factorworld.assets.scenes import metaworld_xml
    from lerobot_factorworld.scene.build import load_task_spec
    from lerobot_factorworld.tasks import get_task

    spec = get_task(task)
    model = load_task_spec(spec).compile()
    base = Path(metaworld_xml(spec)).parent

    def name(adr: int) -> str:
        rel = os.path.normpath(base / model.paths[adr:].split(b"\0", 1)[0].decode())
        return f"metaworld:{Path(rel).relative_to(A.metaworld_assets_dir()).as_posix()}"

    roots = {model.body(b).id for b in spec.object_bodies}
    textures, meshes, object_textures = set(), set(), set()
    for g in range(model.ngeom):
        mat = int(model.geom_matid[g])
        if model.geom_group[g] > 2 or model.geom_rgba[g][3] == 0 or (mat >= 0 and model.mat_rgba[mat][3] == 0):
            continue
        body = int(model.geom_bodyid[g])
        while body and body not in roots:
            body = int(model.body_parentid[body])
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            meshes.add(name(model.mesh_pathadr[model.geom_dataid[g]]))
        for tex in model.mat_texid[mat] if mat >= 0 else ():
            if tex >= 0 and model.tex_pathadr[tex] >= 0:
                textures.add(name(model.tex_pathadr[tex]))
                if body in roots:
                    object_textures.add(name(model.tex_pathadr[tex]))
    return textures, {m for m in meshes if m.removeprefix("metaworld:") in A.METAWORLD_MESH_FAMILIES}, object_textures


@pytest.mark.parametrize(
    ("task", "meshes", "object_textures"),
    [
        ("faucet-open", {"faucet/faucetbase.stl", "faucet/faucethead.stl"}, {"metal2.png"}),
        ("basketball", {"basketball/basketballouter.stl", "basketball/hoop.stl"}, set()),
        ("bin-picking", {"bin/bin.stl"}, set()),
        ("button-press-wall", {"buttonbox/stopbutton.stl"}, {"metal1.png"}),
        ("door-open", {"doorlock/door_handle.stl"}, {"metal1.png", "metal2.png"}),
        ("window-open", set(), set()),
    ],
)
def test_scene_assets_are_what_the_compiled_scene_shows(task: str, meshes: set[str], object_textures: set[str]) -> None:
    from lerobot_factorworld.assets.scenes import scene_assets

    shown = scene_assets(task)
    assert (set(shown.textures), set(shown.meshes), set(shown.object_textures)) == _shown_in_compiled_scene(task)
    assert set(shown.meshes) == {f"metaworld:objects/meshes/{m}" for m in meshes}
    assert set(shown.object_textures) == {f"metaworld:textures/{t}" for t in object_textures}
    assert set(shown.object_meshes) <= set(shown.meshes) and set(shown.object_textures) <= set(shown.textures)
    assert {A.DEFAULT_TABLE_TEXTURE, A.DEFAULT_FLOOR_TEXTURE} <= set(shown.textures)


def test_textures_any_default_scene_shows_are_never_held_out() -> None:
    """The walls' bricks and the fixtures' metal are seen in training, like the table's wood."""
    from lerobot_factorworld.assets.scenes import scene_assets
    from lerobot_factorworld.tasks import TASKS

    shown = {name for task in TASKS for name in scene_assets(task).textures}
    walls_and_fixtures = {f"metaworld:textures/{t}" for t in ("brick1.png", "metal1.png", "metal2.png", "wood4.png")}
    assert walls_and_fixtures <= shown
    assert set(A.seen_families("texture")) == {A.asset_family(n) for n in shown}
    for seed in (0, 1, 2):
        held_out = {A.asset_family(n) for n in A.split_names("texture", "eval", seed=seed)}
        assert not held_out & set(A.seen_families("texture")), seed
    assert shown <= set(A.split_names("texture", "train"))


def _flat(text: str) -> str:
    return " ".join(text.split())


def test_docs_state_the_stored_split_counts_and_families() -> None:
    doc = json.loads(library.SPLITS_FILE.read_text(encoding="utf-8"))
    counts, splits = doc["counts"], doc["splits"]

    def side(kind: str, split: str) -> str:
        return f"{counts['family'][kind][split]} ({len(splits['family'][kind]['families'][split])} families)"

    factors_md = _flat((REPO / "docs" / "factors.md").read_text(encoding="utf-8"))
    row = f"| `family` (default) | {side('texture', 'train')} / {side('texture', 'eval')} | "
    assert row + f"{side('shape', 'train')} / {side('shape', 'eval')} |" in factors_md
    v = counts["variant"]
    assert f"| `variant` | {v['texture']['train']} / {v['texture']['eval']} (" in factors_md
    assert f"| {v['shape']['train']} / {v['shape']['eval']} (" in factors_md
    held = "; ".join(
        f"{kind}s " + ", ".join(f"`{f}`" for f in splits["family"][kind]["families"]["eval"]) for kind in A.KINDS
    )
    assert f"Held out by the family split: {held}." in factors_md
    f = counts["family"]
    readme = _flat((REPO / "README.md").read_text(encoding="utf-8"))
    assert (
        f"textures {f['texture']['train']} train / {f['texture']['eval']} eval, shapes {f['shape']['train']} / "
        f"{f['shape']['eval']};" in readme
    )
    assert f"({v['texture']['train']} / {v['texture']['eval']}, {v['shape']['train']} / {v['shape']['eval']})" in readme


def test_other_seed_resplits_builtin_pool() -> None:
    a, b = (
        A.split_names("shape", "eval", seed=1, mode="variant"),
        A.split_names("shape", "eval", seed=1, mode="variant"),
    )
    assert a == b
    assert a != A.split_names("shape", "eval", mode="variant")
    assert not set(a) & set(A.split_names("shape", "train", seed=1, mode="variant"))


@pytest.mark.parametrize(("kind", "min_train", "min_eval"), [("texture", 81, 81), ("shape", 100, 70)])
def test_family_split_is_seeded(kind: str, min_train: int, min_eval: int) -> None:
    by_seed = {}
    for seed in (0, 1, 2):
        train, evals = A.split_names(kind, "train", seed=seed), A.split_names(kind, "eval", seed=seed)
        assert (train, evals) == (A.split_names(kind, "train", seed=seed), A.split_names(kind, "eval", seed=seed))
        assert len(train) >= min_train and len(evals) >= min_eval
        assert not {A.asset_family(n) for n in train} & {A.asset_family(n) for n in evals}
        assert set(A.seen_families(kind)) <= {A.asset_family(n) for n in train}
        by_seed[seed] = tuple(sorted({A.asset_family(n) for n in evals}))
    assert len(set(by_seed.values())) == 3  # another seed holds other families out
    assert by_seed[0] == tuple(
        json.loads(library.SPLITS_FILE.read_text())["splits"]["family"][kind]["families"]["eval"]
    )


# ----------------------------------------------------------------------------------------------------------
# determinism


_PROBE_TEXTURES = ("proc:marble-003", "proc:voronoi-010", "proc:wood-001", "metaworld:textures/wood2.png")
_PROBE_SHAPES = (
    "proc:mug-004",
    "proc:hull-007",
    "proc:blocks-002",
    "metaworld:objects/meshes/coffeemachine/mug.stl",
)
# run here and in a fresh interpreter; prints sha256 digests of a few assets as JSON
_DIGEST_SCRIPT = f"""
import hashlib, json
from lerobot_factorworld import assets as A
out = [hashlib.sha256(A.load_texture(n, 64).tobytes()).hexdigest() for n in {_PROBE_TEXTURES!r}]
for n in {_PROBE_SHAPES!r}:
    m = A.load_mesh(n)
    out.append(hashlib.sha256(m.vertices.tobytes() + m.faces.tobytes()).hexdigest())
print(json.dumps(out))
"""


def test_same_name_same_asset_in_process_and_cache_is_read_only() -> None:
    from lerobot_factorworld.assets.shapes import generate_shape
    from lerobot_factorworld.assets.textures import generate_texture
    from lerobot_factorworld.core.rng import stable_seed

    for name in _PROBE_TEXTURES[:3]:
        fresh = generate_texture(name[5:].rsplit("-", 1)[0], stable_seed(name), 128)
        np.testing.assert_array_equal(A.load_texture(name), fresh)
        assert A.load_texture(name) is A.load_texture(name)
        assert not A.load_texture(name).flags.writeable
    for name in _PROBE_SHAPES[:3]:
        fresh = generate_shape(name[5:].rsplit("-", 1)[0], stable_seed(name))
        np.testing.assert_array_equal(A.load_mesh(name).vertices, fresh.vertices)
        np.testing.assert_array_equal(A.load_mesh(name).faces, fresh.faces)
        assert not A.load_mesh(name).vertices.flags.writeable
    assert not np.array_equal(A.load_texture("proc:checker-000"), A.load_texture("proc:checker-001"))


def test_same_name_same_asset_across_processes(capsys: pytest.CaptureFixture[str]) -> None:
    exec(_DIGEST_SCRIPT, {})
    here = json.loads(capsys.readouterr().out)
    env = dict(os.environ, PYTHONHASHSEED="12345")  # a different hash() salt must not matter
    out = subprocess.run(
        [sys.executable, "-c", _DIGEST_SCRIPT], capture_output=True, text=True, check=True, env=env, cwd=REPO
    )
    assert json.loads(out.stdout.strip().splitlines()[-1]) == here


# ----------------------------------------------------------------------------------------------------------
# textures


def test_every_builtin_texture_is_valid_distinct_and_tileable() -> None:
    names = A.builtin_names("texture")
    imgs = np.stack([A.load_texture(n) for n in names])
    assert imgs.shape == (len(names), 128, 128, 3) and imgs.dtype == np.uint8
    assert A.load_texture(names[0], 32).shape == (32, 32, 3)
    # pairwise distinct, not just by a pixel: compare 16x16 block means
    small = imgs.reshape(len(names), 16, 8, 16, 8, 3).mean(axis=(2, 4))
    diff = np.abs(small[:, None] - small[None]).mean(axis=(2, 3, 4))
    np.fill_diagonal(diff, np.inf)
    i, j = np.unravel_index(np.argmin(diff), diff.shape)
    assert diff[i, j] > 3.0, f"{names[i]} and {names[j]} look the same"
    # not flat: every procedural texture has visible structure
    proc = np.array([n.startswith("proc:") for n in names])
    assert (imgs[proc].reshape(int(proc.sum()), -1, 3).std(axis=1).max(axis=1) > 8).all()
    # procedural textures tile: the wrap-around seam is no stronger than edges inside the image
    for name, img in zip(names, imgs, strict=True):
        if not name.startswith("proc:"):
            continue
        im = img.astype(np.float64)
        inner_c = np.abs(np.diff(im, axis=1)).mean(axis=(0, 2)).max()
        inner_r = np.abs(np.diff(im, axis=0)).mean(axis=(1, 2)).max()
        assert np.abs(im[:, 0] - im[:, -1]).mean() <= 1.5 * inner_c + 1.0, name
        assert np.abs(im[0] - im[-1]).mean() <= 1.5 * inner_r + 1.0, name


# ----------------------------------------------------------------------------------------------------------
# meshes


def test_every_builtin_mesh_is_normalised_and_clean() -> None:
    for name in A.builtin_names("shape"):
        m = A.load_mesh(name)
        v, f = m.vertices, m.faces
        assert v.dtype == np.float32 and f.dtype == np.int32 and v.shape[1] == 3 and f.shape[1] == 3, name
        assert len(v) >= 4 and f.min() >= 0 and f.max() < len(v), name
        lo, hi = v.min(axis=0), v.max(axis=0)
        assert abs(float((hi - lo).max()) - 1.0) < 1e-6, name
        assert np.allclose((lo[:2] + hi[:2]) / 2, 0.0, atol=1e-6) and lo[2] == 0.0, name
        assert face_areas(v.astype(np.float64), f).min() > 1e-10, name
        assert signed_volume(v, f) > 0, name
        assert np.linalg.svd(v - v.mean(axis=0), compute_uv=False)[2] > 1e-3, name
        if name.startswith("proc:"):
            assert is_watertight(f), name
            assert len(f) <= 1000, name


def test_all_builtin_meshes_compile_in_one_mujoco_spec() -> None:
    names = A.builtin_names("shape")
    spec = mujoco.MjSpec()
    for k, name in enumerate(names):
        m = A.load_mesh(name)
        spec.add_mesh(name=f"mesh{k}", uservert=m.vertices.ravel().tolist(), userface=m.faces.ravel().tolist())
        body = spec.worldbody.add_body(name=f"body{k}", pos=[k % 16, k // 16, 0.0])
        body.add_freejoint()  # free bodies exercise MuJoCo's mass/inertia computation from the mesh
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"mesh{k}")
    model = spec.compile()
    assert model.nmesh == len(names)
    assert (model.body_mass[1:] > 0).all()


# ----------------------------------------------------------------------------------------------------------
# user folders


def _write_user_folder(root: Path) -> None:
    rng = np.random.default_rng(0)
    (root / "sub").mkdir(parents=True)
    for i in range(5):
        Image.fromarray(rng.integers(0, 256, (40 + i, 30, 3), dtype=np.uint8)).save(root / f"tex{i}.png")
    Image.fromarray(rng.integers(0, 256, (20, 20, 3), dtype=np.uint8)).save(root / "sub" / "photo.jpg")
    (root / "notes.txt").write_text("ignored")
    (root / ".hidden.png").write_bytes(b"not an image")
    cube_v = [(x, y, z) for x in (0, 2) for y in (0, 1) for z in (0, 3)]
    quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]  # outward
    obj = "\n".join([f"v {x} {y} {z}" for x, y, z in cube_v] + [f"f {a}/1 {b}/1 {c}/1 {d}/1" for a, b, c, d in quads])
    (root / "cube.obj").write_text(obj + "\n")
    tetra = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    tris = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    ascii_stl = "solid t\n" + "".join(
        "facet normal 0 0 0\nouter loop\n"
        + "".join(f"vertex {' '.join(map(str, tetra[i]))}\n" for i in t)
        + "endloop\nendfacet\n"
        for t in tris
    )
    (root / "tetra.stl").write_text(ascii_stl + "endsolid t\n")
    A.write_stl(root / "sub" / "torus.stl", A.load_mesh("proc:torus-001"))
    A.write_obj(root / "sub" / "gear.obj", A.load_mesh("proc:gear-002"))


def test_user_folder_split_and_loading(tmp_path: Path) -> None:
    folder = tmp_path / "mine"
    _write_user_folder(folder)
    for kind, n_files in (("texture", 6), ("shape", 4)):
        train = A.split_names(kind, "train", folder=folder)
        evals = A.split_names(kind, "eval", folder=folder)
        assert train and evals and not set(train) & set(evals)
        assert sorted(train + evals) == sorted(A.folder_names(kind, folder))
        assert len(train) + len(evals) == n_files
        assert all(n.startswith("file:/") for n in train + evals)
        assert A.split_names(kind, "eval", folder=str(folder)) == evals  # str or Path
    for name in A.folder_names("texture", folder):
        img = A.load_texture(name, 64)
        assert img.shape == (64, 64, 3) and img.dtype == np.uint8
    spec = mujoco.MjSpec()
    for k, name in enumerate(A.folder_names("shape", folder)):
        m = A.load_mesh(name)
        assert abs(float(m.extents.max()) - 1.0) < 1e-6 and signed_volume(m.vertices, m.faces) > 0
        spec.add_mesh(name=f"m{k}", uservert=m.vertices.ravel().tolist(), userface=m.faces.ravel().tolist())
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"m{k}")
    spec.compile()
    np.testing.assert_allclose(A.load_mesh(f"file:{folder / 'cube.obj'}").extents, [2 / 3, 1 / 3, 1.0], atol=1e-6)
    # the split depends on relative paths only: a copy elsewhere splits the same way
    copy = tmp_path / "elsewhere" / "copy"
    shutil.copytree(folder, copy)
    rel = {n.split("/mine/", 1)[1] for n in A.split_names("texture", "eval", folder=folder)}
    assert rel == {n.split("/copy/", 1)[1] for n in A.split_names("texture", "eval", folder=copy)}


def test_user_folder_family_split_keeps_subfolders_whole(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    layout = {"wood/a.png": 0, "wood/b.png": 0, "wood/deep/c.png": 0, "tiles/a.png": 0, "tiles/b.png": 0}
    layout |= {"cloth/a.png": 0, "cloth/b.jpg": 0, "one.png": 0, "two.png": 0}
    for rel in layout:
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(rng.integers(0, 256, (8, 8, 3), dtype=np.uint8)).save(tmp_path / rel)
    families = A.asset_families("texture", tmp_path)
    assert sorted(set(families.values())) == ["cloth", "one.png", "tiles", "two.png", "wood"]
    assert A.asset_family(f"file:{tmp_path / 'wood/deep/c.png'}", tmp_path) == "wood"
    train, evals = A.split_names("texture", "train", tmp_path), A.split_names("texture", "eval", tmp_path)
    assert sorted(train + evals) == sorted(families) and train and evals
    assert not {families[n] for n in train} & {families[n] for n in evals}
    assert {A.asset_family(n, tmp_path) for n in evals} == {families[n] for n in evals}
    # a flat folder: every file is its own family, so both split modes agree
    flat = tmp_path / "flat"
    flat.mkdir()
    for i in range(5):
        Image.fromarray(rng.integers(0, 256, (8, 8, 3), dtype=np.uint8)).save(flat / f"t{i}.png")
    assert A.split_names("texture", "eval", flat) == A.split_names("texture", "eval", flat, mode="variant")
    # one family cannot be split by family: the error says what to do
    single = tmp_path / "single"
    (single / "only").mkdir(parents=True)
    for i in range(3):
        Image.fromarray(rng.integers(0, 256, (8, 8, 3), dtype=np.uint8)).save(single / "only" / f"t{i}.png")
    with pytest.raises(ValueError, match=r"at least 2 texture families.*asset_split=variant"):
        A.split_names("texture", "train", single)
    assert len(A.split_names("texture", "eval", single, mode="variant")) == 1


def test_big_user_mesh_is_simplified(tmp_path: Path) -> None:
    n = 120  # a UV sphere with ~28k faces
    th, ph = np.meshgrid(np.linspace(0.01, np.pi - 0.01, n), np.linspace(0, 2 * np.pi, 2 * n, endpoint=False))
    v = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1).reshape(-1, 3)
    idx = np.arange(2 * n * n).reshape(2 * n, n)
    a, b = idx[:, :-1], idx[:, 1:]
    c, d = np.roll(a, -1, axis=0), np.roll(b, -1, axis=0)
    f = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])
    path = tmp_path / "ball.obj"
    A.write_obj(path, A.Mesh(v.astype(np.float32), f.astype(np.int32)))
    m = A.load_mesh(f"file:{path}")
    assert len(f) > A.MAX_FACES >= len(m.faces) > 100
    spec = mujoco.MjSpec()
    spec.add_mesh(name="ball", uservert=m.vertices.ravel().tolist(), userface=m.faces.ravel().tolist())
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="ball")
    spec.compile()


# ----------------------------------------------------------------------------------------------------------
# errors name the valid choices


def test_error_messages_name_valid_choices(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unknown split 'test'; valid splits: train, eval"):
        A.split_names("texture", "test")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="unknown asset split 'random'; valid asset splits: family, variant"):
        A.split_names("texture", "train", mode="random")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="valid kinds: texture, shape"):
        A.split_names("sound", "train")  # type: ignore[arg-type]
    with pytest.raises(FileNotFoundError, match=str(tmp_path / "nope")):
        A.split_names("texture", "train", folder=tmp_path / "nope")
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / "readme.txt").write_text("no images here")
    with pytest.raises(ValueError, match=r"\.png, \.jpg, \.jpeg"):
        A.split_names("texture", "train", folder=tmp_path / "empty")
    with pytest.raises(ValueError, match=r"\.stl, \.obj"):
        A.split_names("shape", "eval", folder=tmp_path / "empty")
    with pytest.raises(ValueError, match="unknown procedural family 'blob'.*checker.*torus"):
        A.load_texture("proc:blob-001")
    with pytest.raises(ValueError, match="texture families: .*checker"):
        A.load_texture("proc:torus-001")
    with pytest.raises(ValueError, match="shape families: .*torus"):
        A.load_mesh("proc:checker-001")
    with pytest.raises(ValueError, match="proc:<family>-<NNN>"):
        A.load_texture("proc:checker-1")
    with pytest.raises(ValueError, match="metaworld:"):
        A.load_mesh("http://example.com/x.stl")
    with pytest.raises(FileNotFoundError, match="missing.png"):
        A.load_texture(f"file:{tmp_path / 'missing.png'}")
    with pytest.raises(FileNotFoundError, match="nothing.png"):
        A.load_texture("metaworld:textures/nothing.png")
    (tmp_path / "broken.png").write_bytes(b"definitely not a png")
    with pytest.raises(ValueError, match="cannot read texture image"):
        A.load_texture(f"file:{tmp_path / 'broken.png'}")
    with pytest.raises(ValueError, match="absolute"):
        A.load_texture("file:relative/x.png")
    with pytest.raises(ValueError, match=r"\.stl, \.obj"):
        A.load_mesh("metaworld:textures/wood2.png")
    with pytest.raises(ValueError, match="at least 2"):
        one = tmp_path / "one"
        one.mkdir()
        Image.new("RGB", (4, 4)).save(one / "a.png")
        A.split_names("texture", "train", folder=one)
