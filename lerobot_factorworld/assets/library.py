"""Asset names, built-in pools, train/eval splits and cached loading.

Names are self-describing strings, so a saved configuration reloads the same asset on any machine:

* ``proc:<family>-<NNN>``: procedural texture or shape, a pure function of the name;
* ``metaworld:<path inside metaworld/assets>``: a file shipped with the installed ``metaworld`` package;
* ``file:<absolute path>``: a user's own image (.png/.jpg/.jpeg) or mesh (.stl/.obj).

Every asset belongs to a *family* (:func:`asset_family`): a procedural family, the family a Meta-World
file looks like, or a user's subfolder. Two train/eval splits exist: ``family`` (the default) holds whole
families out, so "new" textures and shapes really are new kinds; ``variant`` splits name by name. The
families the default scenes show (:func:`seen_families`) always go to train.

The built-in splits live in ``asset_splits.json`` (written by ``scripts/make_asset_splits.py``), which is
the single source of truth; it carries a sha256 of its lists so hand edits are caught at load.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal, get_args

import numpy as np
from PIL import Image

from ..core.rng import stable_seed
from ..core.splits import SPLITS, Split, check_split
from .mesh import Mesh, normalize_mesh
from .mesh_io import MESH_EXTENSIONS, read_mesh_file
from .shapes import SHAPE_FAMILIES, generate_shape
from .textures import TEXTURE_FAMILIES, generate_texture

AssetKind = Literal["texture", "shape"]
KINDS: tuple[str, ...] = get_args(AssetKind)
AssetSplitMode = Literal["family", "variant"]
ASSET_SPLITS: tuple[str, ...] = get_args(AssetSplitMode)
DEFAULT_ASSET_SPLIT: AssetSplitMode = "family"
"""``family`` holds whole families out (eval assets are unlike anything in train, as the paper's unseen
images and scanned objects); ``variant`` splits the pool name by name (eval has new variants of seen families)."""

TEXTURE_EXTENSIONS: tuple[str, ...] = (".png", ".jpg", ".jpeg")
TRAIN_FRACTION: dict[str, float] = {"texture": 0.5, "shape": 0.6}
"""Share of a pool that goes to ``train``; shapes get more training variety (Factor World used 100:70)."""

PAPER_SPLIT_SIZES: dict[str, dict[str, int]] = {
    "texture": {"train": 81, "eval": 81},
    "shape": {"train": 100, "eval": 70},
}
"""The paper's pools (81 / 81 images, 100 / 70 scanned objects): every built-in split is at least as large."""

VARIANTS_PER_FAMILY = 12
SPLITS_SEED = 0
SPLITS_FILE = Path(__file__).with_name("asset_splits.json")

METAWORLD_TEXTURE_FAMILIES: dict[str, str] = {
    "textures/brick1.png": "bricks",
    "textures/darkwood.png": "wood",
    "textures/floor1.png": "grid",  # square floor tiles with grout lines
    "textures/floor2.png": "grid",
    "textures/granite.png": "terrazzo",  # stone speckles
    "textures/light_wood.png": "wood",
    "textures/light_wood_v2.png": "wood",
    "textures/light_wood_v3.jpeg": "wood",
    "textures/light_wood_v3.png": "wood",
    "textures/marble.png": "marble",
    "textures/metal.png": "plain",
    "textures/metal1.png": "plain",
    "textures/metal2.png": "plain",
    "textures/navy_blue.png": "plain",
    "textures/plaster1.png": "plain",
    "textures/real_door.png": "wood",
    "textures/tennis.png": "court",
    "textures/wood.png": "wood",
    "textures/wood1.png": "wood",
    "textures/wood2.png": "wood",
    "textures/wood3.png": "wood",
    "textures/wood4.png": "wood",
    "textures/wood_light.png": "wood",
}
"""Every texture Meta-World ships (all are visibly different images) -> the family it looks like: a
procedural family where one matches (its woods are ``wood``), else a Meta-World-only family (``plain``:
near-uniform metal, plaster and cloth; ``court``: the tennis court)."""

METAWORLD_MESH_FAMILIES: dict[str, str] = {
    "objects/meshes/assembly_peg/assembly_peg_handle.stl": "box",
    "objects/meshes/assembly_peg/assembly_peg_ring.stl": "torus",
    "objects/meshes/basketball/basketballouter.stl": "ellipsoid",
    "objects/meshes/basketball/hoop.stl": "torus",
    "objects/meshes/bin/bin.stl": "open_box",
    "objects/meshes/block/block.stl": "box",
    "objects/meshes/buttonbox/button.stl": "cylinder",
    "objects/meshes/buttonbox/stopbutton.stl": "cylinder",
    "objects/meshes/coffeemachine/mug.stl": "bowl",  # a handle-less cup: the bowl family's cup/pot variant
    "objects/meshes/coffeemachine/spout.stl": "capsule",
    "objects/meshes/dial/dial.stl": "cylinder",
    "objects/meshes/doorlock/door_handle.stl": "hardware",
    "objects/meshes/drawer/drawer.stl": "open_box",
    "objects/meshes/faucet/faucetbase.stl": "hardware",
    "objects/meshes/faucet/faucethead.stl": "cylinder",
    "objects/meshes/golf_club/club_head.stl": "capsule",
    "objects/meshes/hammer/hammerhead.stl": "hardware",
    "objects/meshes/hammer/nail.stl": "hardware",
    "objects/meshes/handle_press/handle_press_grip.stl": "cylinder",
    "objects/meshes/lever/lever_handle.stl": "ellipsoid",  # a ball
    "objects/meshes/lever/lever_rodbase.stl": "cylinder",
    "objects/meshes/peg_block/block_outer.stl": "open_box",
    "objects/meshes/plug/plug.stl": "hardware",
    "objects/meshes/plug/plug_head.stl": "cylinder",
    "objects/meshes/puck/puck.stl": "cylinder",
    "objects/meshes/stick/stick.stl": "box",
    "objects/meshes/thermos/therm_base.stl": "cylinder",
    "objects/meshes/thermos/therm_body.stl": "capsule",
    "objects/meshes/thermos/therm_cap.stl": "cylinder",
}
"""Small, object-like Meta-World meshes (< 2000 faces; fixtures such as the table or robot are left out)
-> the family they look like: a procedural family where one matches (the puck is a ``cylinder``), else a
Meta-World-only family (``open_box``: bin, drawer, peg block; ``hardware``: handles, posts, plug, hammer)."""

METAWORLD_TEXTURES: tuple[str, ...] = tuple(METAWORLD_TEXTURE_FAMILIES)
METAWORLD_MESHES: tuple[str, ...] = tuple(METAWORLD_MESH_FAMILIES)

DEFAULT_TABLE_TEXTURE = "metaworld:textures/wood2.png"
DEFAULT_FLOOR_TEXTURE = "metaworld:textures/floor2.png"
"""What Meta-World's default scene shows (``T_table`` and ``T_floor`` in its ``scene/basic_scene*.xml``)."""

_PROC_RE = re.compile(r"^proc:([a-z_]+)-(\d{3})$")
_NAME_HELP = "expected 'proc:<family>-<NNN>', 'metaworld:<path inside metaworld/assets>' or 'file:<absolute path>'"


# ----------------------------------------------------------------------------------------------------------
# names


def check_kind(kind: str) -> AssetKind:
    if kind not in KINDS:
        raise ValueError(f"unknown asset kind {kind!r}; valid kinds: {', '.join(KINDS)}")
    return kind  # type: ignore[return-value]


def check_asset_split(mode: str) -> AssetSplitMode:
    """``mode`` if it names an asset split mode, else a ``ValueError`` naming the valid ones."""
    if mode not in ASSET_SPLITS:
        raise ValueError(f"unknown asset split {mode!r}; valid asset splits: {', '.join(ASSET_SPLITS)}")
    return mode  # type: ignore[return-value]


def _extensions(kind: AssetKind) -> tuple[str, ...]:
    return TEXTURE_EXTENSIONS if kind == "texture" else MESH_EXTENSIONS


def metaworld_assets_dir() -> Path:
    """The ``assets`` folder of the installed ``metaworld`` (found without importing its heavy package)."""
    spec = importlib.util.find_spec("metaworld")
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError("metaworld is not installed; 'metaworld:' assets need it")
    return Path(list(spec.submodule_search_locations)[0]) / "assets"


def asset_kind(name: str) -> AssetKind:
    """``"texture"`` or ``"shape"`` for a valid asset name (from the family or the file extension)."""
    scheme, _, rest = name.partition(":")
    if scheme == "proc":
        family = _proc_family(name)
        return "texture" if family in TEXTURE_FAMILIES else "shape"
    if scheme in ("metaworld", "file"):
        suffix = Path(rest).suffix.lower()
        for kind in KINDS:
            if suffix in _extensions(kind):  # type: ignore[arg-type]
                return kind  # type: ignore[return-value]
        raise ValueError(
            f"{name!r}: unsupported extension {suffix!r}; textures: {', '.join(TEXTURE_EXTENSIONS)}, "
            f"meshes: {', '.join(MESH_EXTENSIONS)}"
        )
    raise ValueError(f"unknown asset name {name!r}; {_NAME_HELP}")


def _proc_family(name: str) -> str:
    m = _PROC_RE.match(name)
    if m is None:
        raise ValueError(f"bad procedural asset name {name!r}; expected 'proc:<family>-<NNN>' (e.g. proc:checker-007)")
    family = m.group(1)
    if family not in TEXTURE_FAMILIES and family not in SHAPE_FAMILIES:
        raise ValueError(
            f"unknown procedural family {family!r} in {name!r}; "
            f"texture families: {', '.join(TEXTURE_FAMILIES)}; shape families: {', '.join(SHAPE_FAMILIES)}"
        )
    return family


def builtin_families(kind: AssetKind) -> tuple[str, ...]:
    """Every built-in family of ``kind``: the procedural ones, then the Meta-World-only ones (sorted)."""
    kind = check_kind(kind)
    proc = TEXTURE_FAMILIES if kind == "texture" else SHAPE_FAMILIES
    shipped = METAWORLD_TEXTURE_FAMILIES if kind == "texture" else METAWORLD_MESH_FAMILIES
    return proc + tuple(sorted(set(shipped.values()) - set(proc)))


def asset_family(name: str, folder: str | Path | None = None) -> str:
    """The family of an asset: what the family split holds out as a whole, and what "look-alike" means.

    ``proc:`` names: their procedural family; curated Meta-World files: the family they look like
    (:data:`METAWORLD_TEXTURE_FAMILIES`, :data:`METAWORLD_MESH_FAMILIES`); a file inside ``folder``: its
    top-level subfolder (one subfolder per family), or the file itself when it lies directly in ``folder``;
    any other file is a family of its own (its name).
    """
    scheme, _, rest = name.partition(":")
    if scheme == "proc":
        return _proc_family(name)
    if scheme == "metaworld":
        return METAWORLD_TEXTURE_FAMILIES.get(rest) or METAWORLD_MESH_FAMILIES.get(rest) or name
    if scheme == "file":
        if folder is None:
            return name
        try:
            rel = Path(rest).relative_to(Path(folder).expanduser().resolve())
        except ValueError:
            return name
        return _folder_family(rel.as_posix())
    raise ValueError(f"unknown asset name {name!r}; {_NAME_HELP}")


def _folder_family(rel: str) -> str:
    """Family of a file from its path relative to a user folder: the top-level subfolder, else the file."""
    return rel.split("/", 1)[0]


def _file_path(name: str, kind: AssetKind) -> Path:
    """Resolve a ``metaworld:`` or ``file:`` name to an existing file of the right kind."""
    scheme, _, rest = name.partition(":")
    if scheme == "metaworld":
        rel = Path(rest)
        if rel.is_absolute() or ".." in rel.parts or not rest:
            raise ValueError(f"{name!r}: a metaworld asset is a relative path inside metaworld/assets")
        path = metaworld_assets_dir() / rel
    elif scheme == "file":
        path = Path(rest)
        if not path.is_absolute():
            raise ValueError(f"{name!r}: a file asset needs an absolute path so that it reloads anywhere")
    else:
        raise ValueError(f"unknown asset name {name!r}; {_NAME_HELP}")
    if path.suffix.lower() not in _extensions(kind):
        raise ValueError(f"{name!r} is not a {kind} file; supported extensions: {', '.join(_extensions(kind))}")
    if not path.is_file():
        raise FileNotFoundError(f"asset file not found: {path} (from {name!r})")
    return path


# ----------------------------------------------------------------------------------------------------------
# loading


@functools.lru_cache(maxsize=1024)
def _texture_cached(name: str, size: int) -> np.ndarray:
    if name.startswith("proc:"):
        family = _proc_family(name)
        if family not in TEXTURE_FAMILIES:
            raise ValueError(f"{name!r} is a shape, not a texture; texture families: {', '.join(TEXTURE_FAMILIES)}")
        img = generate_texture(family, stable_seed(name), size)
    else:
        path = _file_path(name, "texture")
        try:
            with Image.open(path) as im:
                img = np.array(im.convert("RGB").resize((size, size), Image.Resampling.LANCZOS), dtype=np.uint8)
        except OSError as exc:  # PIL's UnidentifiedImageError is an OSError
            raise ValueError(f"cannot read texture image {path} (from {name!r}): {exc}") from exc
    img.flags.writeable = False
    return img


def load_texture(name: str, size: int = 128) -> np.ndarray:
    """``size`` x ``size`` x 3 uint8 RGB image for a texture name (cached; the array is read-only)."""
    if not isinstance(size, int | np.integer) or size < 1:
        raise ValueError(f"texture size must be a positive integer, got {size!r}")
    return _texture_cached(name, int(size))


@functools.lru_cache(maxsize=1024)
def load_mesh(name: str) -> Mesh:
    """Normalised :class:`Mesh` for a shape name (cached; arrays are read-only).

    Files are cleaned, oriented outwards and normalised exactly like procedural shapes; meshes above
    :data:`~lerobot_factorworld.assets.mesh.MAX_FACES` faces are simplified.
    """
    if name.startswith("proc:"):
        family = _proc_family(name)
        if family not in SHAPE_FAMILIES:
            raise ValueError(f"{name!r} is a texture, not a shape; shape families: {', '.join(SHAPE_FAMILIES)}")
        return generate_shape(family, stable_seed(name))
    path = _file_path(name, "shape")
    try:
        return normalize_mesh(*read_mesh_file(path))
    except ValueError as exc:
        raise ValueError(f"cannot use mesh {name!r}: {exc}") from exc


def clear_cache() -> None:
    """Forget cached textures and meshes (e.g. after editing a user file in place)."""
    _texture_cached.cache_clear()
    load_mesh.cache_clear()


# ----------------------------------------------------------------------------------------------------------
# pools and splits


def builtin_names(kind: AssetKind) -> tuple[str, ...]:
    """Sorted built-in pool: ``VARIANTS_PER_FAMILY`` variants per procedural family plus Meta-World files."""
    kind = check_kind(kind)
    families = TEXTURE_FAMILIES if kind == "texture" else SHAPE_FAMILIES
    shipped = METAWORLD_TEXTURES if kind == "texture" else METAWORLD_MESHES
    names = [f"proc:{f}-{i:03d}" for f in families for i in range(VARIANTS_PER_FAMILY)]
    names += [f"metaworld:{p}" for p in shipped]
    return tuple(sorted(names))


def seen_families(kind: AssetKind) -> tuple[str, ...]:
    """Built-in families the default scenes show, which the family split always puts in ``train``, as
    ``asset_splits.json`` records them (computed from the tasks' scenes by
    :func:`lerobot_factorworld.assets.split_document.scene_seen_families` when the file is written)."""
    return tuple(_document()["seen_families"][check_kind(kind)])


def _rank(seed: int, key: str) -> tuple[bytes, str]:
    """Machine-independent sort key of a seeded permutation: sha256 of ``(seed, key)``."""
    return hashlib.sha256(f"{seed}\x1f{key}".encode()).digest(), key


def _n_train(n: int, kind: AssetKind) -> int:
    return min(max(round(n * TRAIN_FRACTION[kind]), 1), n - 1)


def split_pool(
    names: Sequence[str], kind: AssetKind, seed: int = 0, keys: Sequence[str] | None = None
) -> dict[str, tuple[str, ...]]:
    """Per-variant split: ``names`` into disjoint, sorted ``train``/``eval`` tuples, item by item.

    The seeded permutation ranks items by sha256 of ``(seed, key)`` (``keys`` default to the names), so it
    is identical on every machine and NumPy version, and adding one item never reshuffles the others.
    """
    kind = check_kind(kind)
    keys = list(names) if keys is None else list(keys)
    if len(keys) != len(names) or len(set(keys)) != len(keys):
        raise ValueError("split keys must be unique and match the names one to one")
    n = len(names)
    if n < 2:
        raise ValueError(f"need at least 2 {kind} assets to make a train/eval split, got {n}")
    order = sorted(range(n), key=lambda i: _rank(seed, keys[i]))
    n_train = _n_train(n, kind)
    return {
        "train": tuple(sorted(names[i] for i in order[:n_train])),
        "eval": tuple(sorted(names[i] for i in order[n_train:])),
    }


def split_pool_by_family(
    names: Sequence[str],
    families: Sequence[str],
    kind: AssetKind,
    seed: int = 0,
    seen: Sequence[str] = (),
) -> dict[str, tuple[str, ...]]:
    """Family split: which families go to ``train`` and which are held out whole in ``eval`` (sorted).

    ``families[i]`` is the family of ``names[i]``. Families in ``seen`` go to ``train`` first; the others
    follow in a seeded, machine-independent order (sha256 of ``(seed, family)``, so adding a family never
    reshuffles the rest) until ``train`` holds :data:`TRAIN_FRACTION` of the names; the rest, at least one
    family, is held out.
    """
    kind = check_kind(kind)
    if len(families) != len(names):
        raise ValueError("families must match the names one to one")
    sizes: dict[str, int] = {}
    for family in families:
        sizes[family] = sizes.get(family, 0) + 1
    if len(sizes) < 2:
        raise ValueError(
            f"need at least 2 {kind} families to hold whole families out, got {len(sizes)} "
            f"({', '.join(sizes) or 'none'}); put the files in subfolders, one per family, or use the "
            "per-variant split (asset_split=variant)"
        )
    first = sorted(set(seen) & set(sizes))
    order = first + sorted(set(sizes) - set(first), key=lambda f: _rank(seed, f))
    target, count, train = _n_train(len(names), kind), 0, []
    for family in order:
        if (count >= target and family not in first) or len(train) == len(order) - 1:
            break
        train.append(family)
        count += sizes[family]
    return {"train": tuple(sorted(train)), "eval": tuple(sorted(set(order) - set(train)))}


def _split_by_family(
    names: Sequence[str], families: Sequence[str], kind: AssetKind, seed: int, seen: Sequence[str] = ()
) -> tuple[dict[str, tuple[str, ...]], dict[str, tuple[str, ...]]]:
    """(names per split, families per split) of the family split."""
    by_split = split_pool_by_family(names, families, kind, seed, seen)
    train = set(by_split["train"])
    return {
        "train": tuple(sorted(n for n, f in zip(names, families, strict=True) if f in train)),
        "eval": tuple(sorted(n for n, f in zip(names, families, strict=True) if f not in train)),
    }, by_split


def builtin_split(
    mode: AssetSplitMode, kind: AssetKind, seed: int, seen: Sequence[str]
) -> dict[str, dict[str, tuple[str, ...]]]:
    """``{"names": {split: names}, "families": {split: families}}`` of the built-in pool, computed, with the
    families in ``seen`` kept in ``train`` by the family split."""
    names = builtin_names(kind)
    families = [asset_family(n) for n in names]
    if mode == "variant":
        return _variant_lists(names, families, split_pool(names, kind, seed))
    by_name, by_family = _split_by_family(names, families, kind, seed, seen)
    return {"names": by_name, "families": by_family}


def _variant_lists(
    names: Sequence[str], families: Sequence[str], by_name: dict[str, tuple[str, ...]]
) -> dict[str, dict[str, tuple[str, ...]]]:
    """The per-variant split's names and the families each side draws from (mostly the same ones)."""
    family = dict(zip(names, families, strict=True))
    by_family = {s: tuple(sorted({family[n] for n in by_name[s]})) for s in SPLITS}
    return {"names": by_name, "families": by_family}


def splits_digest(lists: dict[str, Any]) -> str:
    """sha256 of the split lists (``{mode: {kind: {"names": {split: [..]}, "families": {split: [..]}}}}``),
    as stored in ``asset_splits.json``."""
    return hashlib.sha256(json.dumps(jsonable(lists), sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, (tuple, list)):
        return [jsonable(v) for v in value]
    return value


class AssetSplitsError(RuntimeError):
    """``asset_splits.json`` is missing, malformed, or was edited by hand."""


REGENERATE = "regenerate it with `python scripts/make_asset_splits.py`"


def _document() -> dict[str, Any]:
    """The parsed splits file (read each time: the split lists themselves are cached by :func:`_builtin_splits`)."""
    try:
        doc = json.loads(SPLITS_FILE.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise AssetSplitsError(f"cannot read built-in splits from {SPLITS_FILE} ({exc}); {REGENERATE}") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("seen_families"), dict):
        raise AssetSplitsError(f"{SPLITS_FILE} is malformed (no seen_families); {REGENERATE}")
    return doc


@functools.lru_cache(maxsize=1)
def _builtin_splits() -> dict[str, dict[str, dict[str, dict[str, tuple[str, ...]]]]]:
    regen = REGENERATE
    try:
        doc = _document()
        raw = doc["splits"]
        lists = {
            mode: {
                kind: {part: {s: tuple(raw[mode][kind][part][s]) for s in SPLITS} for part in ("names", "families")}
                for kind in KINDS
            }
            for mode in ASSET_SPLITS
        }
        stored = doc["sha256"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise AssetSplitsError(f"cannot read built-in splits from {SPLITS_FILE} ({exc}); {regen}") from exc
    if splits_digest(lists) != stored:
        raise AssetSplitsError(
            f"{SPLITS_FILE} does not match its sha256 (edited by hand?); built-in splits must come from the "
            f"script: {regen}"
        )
    for mode, by_kind in lists.items():
        for kind, d in by_kind.items():
            problem = _split_problem(mode, kind, d)  # type: ignore[arg-type]
            if problem:
                raise AssetSplitsError(f"{SPLITS_FILE}: {mode} split of {kind}s: {problem}; {regen}")
    return lists


def _split_problem(mode: AssetSplitMode, kind: AssetKind, lists: dict[str, dict[str, tuple[str, ...]]]) -> str:
    """What is wrong with one stored split (empty when nothing): the checks that hold whatever the sha256."""
    names, families = lists["names"], lists["families"]
    if set(names["train"]) & set(names["eval"]):
        return "train and eval overlap"
    if sorted(names["train"] + names["eval"]) != list(builtin_names(kind)):
        return "its names are not the built-in pool (assets were added or removed since it was written)"
    for split in SPLITS:
        if families[split] != tuple(sorted({asset_family(n) for n in names[split]})):
            return f"its {split} families are not the families of its {split} names"
    if mode == "family" and set(families["train"]) & set(families["eval"]):
        return "a family is on both sides of the family split"
    return ""


def _folder_files(kind: AssetKind, folder: str | Path) -> list[tuple[str, str]]:
    """(relative posix path, ``file:`` name) of every supported file under ``folder``, sorted by path."""
    root = Path(folder).expanduser()
    if not root.exists():
        raise FileNotFoundError(f"asset folder not found: {root}")
    if not root.is_dir():
        raise NotADirectoryError(f"asset folder is not a directory: {root}")
    root = root.resolve()
    exts = _extensions(kind)
    found = []
    for p in root.rglob("*"):
        rel = p.relative_to(root)
        if p.suffix.lower() in exts and not any(part.startswith(".") for part in rel.parts) and p.is_file():
            found.append((rel.as_posix(), f"file:{p.as_posix()}"))
    if not found:
        raise ValueError(f"no {kind} files found in {root}; supported extensions: {', '.join(exts)}")
    return sorted(found)


def folder_names(kind: AssetKind, folder: str | Path) -> tuple[str, ...]:
    """``file:`` names of all supported files under ``folder`` (recursive, hidden entries skipped), sorted by
    their path relative to the folder."""
    return tuple(name for _, name in _folder_files(check_kind(kind), folder))


def asset_families(kind: AssetKind, folder: str | Path | None = None) -> dict[str, str]:
    """Name -> family of every asset in the built-in pool, or in ``folder`` (see :func:`asset_family`)."""
    kind = check_kind(kind)
    if folder is None:
        return dict(_builtin_families_of(kind))
    return {name: _folder_family(rel) for rel, name in _folder_files(kind, folder)}


@functools.lru_cache(maxsize=2)
def _builtin_families_of(kind: AssetKind) -> tuple[tuple[str, str], ...]:
    return tuple((name, asset_family(name)) for name in builtin_names(kind))


def _split_lists(
    kind: AssetKind, folder: str | Path | None, seed: int, mode: AssetSplitMode
) -> dict[str, dict[str, tuple[str, ...]]]:
    if folder is None:
        if seed == SPLITS_SEED:
            return _builtin_splits()[mode][kind]
        return builtin_split(mode, kind, seed, seen_families(kind))
    files = _folder_files(kind, folder)
    names, rels = [n for _, n in files], [r for r, _ in files]
    families = [_folder_family(r) for r in rels]
    if mode == "variant":
        return _variant_lists(names, families, split_pool(names, kind, seed, keys=rels))
    by_name, by_family = _split_by_family(names, families, kind, seed)
    return {"names": by_name, "families": by_family}


def split_names(
    kind: AssetKind,
    split: Split,
    folder: str | Path | None = None,
    seed: int = 0,
    mode: AssetSplitMode = DEFAULT_ASSET_SPLIT,
) -> tuple[str, ...]:
    """Asset names of one split, sorted.

    ``mode="family"`` (the default) holds whole families out; ``"variant"`` splits name by name. Without
    ``folder`` the built-in split is read from ``asset_splits.json`` (for ``seed == 0``; another seed
    re-splits the built-in pool with the same function). With ``folder`` the same split function runs on
    the folder's files, keyed by their relative paths (a top-level subfolder is a family), so a copied
    folder splits identically anywhere. The families a side draws from are those of its names
    (:func:`asset_family` with the same ``folder``); ``asset_splits.json`` lists them for the built-in pool.
    """
    kind, split, mode = check_kind(kind), check_split(split), check_asset_split(mode)
    return _split_lists(kind, folder, seed, mode)["names"][split]


def check_asset_folders(texture_folder: str | None, shape_folder: str | None) -> None:
    """User asset folders exist and hold at least one usable file (listing only; nothing is loaded)."""
    for kind, folder in (("texture", texture_folder), ("shape", shape_folder)):
        if folder is not None:
            folder_names(kind, folder)  # raises naming the supported extensions
