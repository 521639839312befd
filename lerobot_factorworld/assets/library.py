"""Asset names, built-in pools, train/eval splits and cached loading.

Names are self-describing strings, so a saved configuration reloads the same asset on any machine:

* ``proc:<family>-<NNN>``: procedural texture or shape, a pure function of the name;
* ``metaworld:<path inside metaworld/assets>``: a file shipped with the installed ``metaworld`` package;
* ``file:<absolute path>``: a user's own image (.png/.jpg/.jpeg) or mesh (.stl/.obj).

The built-in train/eval splits live in ``asset_splits.json`` (written by ``scripts/make_asset_splits.py``),
which is the single source of truth; it carries a sha256 of its lists so hand edits are caught at load.
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

from ._rng import stable_seed
from .mesh import Mesh, normalize_mesh
from .mesh_io import MESH_EXTENSIONS, read_mesh_file
from .shapes import SHAPE_FAMILIES, generate_shape
from .textures import TEXTURE_FAMILIES, generate_texture

AssetKind = Literal["texture", "shape"]
Split = Literal["train", "eval"]
KINDS: tuple[str, ...] = get_args(AssetKind)
SPLITS: tuple[str, ...] = get_args(Split)

TEXTURE_EXTENSIONS: tuple[str, ...] = (".png", ".jpg", ".jpeg")
TRAIN_FRACTION: dict[str, float] = {"texture": 0.5, "shape": 0.6}
"""Share of a pool that goes to ``train``; shapes get more training variety (Factor World used 100:70)."""

VARIANTS_PER_FAMILY = 12
SPLITS_SEED = 0
SPLITS_FILE = Path(__file__).with_name("asset_splits.json")

METAWORLD_TEXTURES: tuple[str, ...] = tuple(
    f"textures/{f}"
    for f in (
        "brick1.png",
        "darkwood.png",
        "floor1.png",
        "floor2.png",
        "granite.png",
        "light_wood.png",
        "light_wood_v2.png",
        "light_wood_v3.jpeg",
        "light_wood_v3.png",
        "marble.png",
        "metal.png",
        "metal1.png",
        "metal2.png",
        "navy_blue.png",
        "plaster1.png",
        "real_door.png",
        "tennis.png",
        "wood.png",
        "wood1.png",
        "wood2.png",
        "wood3.png",
        "wood4.png",
        "wood_light.png",
    )
)
"""Every texture Meta-World ships (all are visibly different images)."""

METAWORLD_MESHES: tuple[str, ...] = tuple(
    f"objects/meshes/{m}.stl"
    for m in (
        "assembly_peg/assembly_peg_handle",
        "assembly_peg/assembly_peg_ring",
        "basketball/basketballouter",
        "basketball/hoop",
        "bin/bin",
        "block/block",
        "buttonbox/button",
        "buttonbox/stopbutton",
        "coffeemachine/mug",
        "coffeemachine/spout",
        "dial/dial",
        "doorlock/door_handle",
        "drawer/drawer",
        "faucet/faucetbase",
        "faucet/faucethead",
        "golf_club/club_head",
        "hammer/hammerhead",
        "hammer/nail",
        "handle_press/handle_press_grip",
        "lever/lever_handle",
        "lever/lever_rodbase",
        "peg_block/block_outer",
        "plug/plug",
        "plug/plug_head",
        "puck/puck",
        "stick/stick",
        "thermos/therm_base",
        "thermos/therm_body",
        "thermos/therm_cap",
    )
)
"""Small, object-like Meta-World meshes (< 2000 faces); fixtures such as the table or robot are left out."""

_PROC_RE = re.compile(r"^proc:([a-z_]+)-(\d{3})$")
_NAME_HELP = "expected 'proc:<family>-<NNN>', 'metaworld:<path inside metaworld/assets>' or 'file:<absolute path>'"


# ----------------------------------------------------------------------------------------------------------
# names


def _check_kind(kind: str) -> AssetKind:
    if kind not in KINDS:
        raise ValueError(f"unknown asset kind {kind!r}; valid kinds: {', '.join(KINDS)}")
    return kind  # type: ignore[return-value]


def _check_split(split: str) -> Split:
    if split not in SPLITS:
        raise ValueError(f"unknown split {split!r}; valid splits: {', '.join(SPLITS)}")
    return split  # type: ignore[return-value]


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
    kind = _check_kind(kind)
    families = TEXTURE_FAMILIES if kind == "texture" else SHAPE_FAMILIES
    shipped = METAWORLD_TEXTURES if kind == "texture" else METAWORLD_MESHES
    names = [f"proc:{f}-{i:03d}" for f in families for i in range(VARIANTS_PER_FAMILY)]
    names += [f"metaworld:{p}" for p in shipped]
    return tuple(sorted(names))


def split_pool(
    names: Sequence[str], kind: AssetKind, seed: int = 0, keys: Sequence[str] | None = None
) -> dict[str, tuple[str, ...]]:
    """Split ``names`` into disjoint, sorted ``train``/``eval`` tuples.

    The seeded permutation ranks items by sha256 of ``(seed, key)`` (``keys`` default to the names), so it
    is identical on every machine and NumPy version, and adding one item never reshuffles the others.
    """
    kind = _check_kind(kind)
    keys = list(names) if keys is None else list(keys)
    if len(keys) != len(names) or len(set(keys)) != len(keys):
        raise ValueError("split keys must be unique and match the names one to one")
    n = len(names)
    if n < 2:
        raise ValueError(f"need at least 2 {kind} assets to make a train/eval split, got {n}")
    order = sorted(range(n), key=lambda i: (hashlib.sha256(f"{seed}\x1f{keys[i]}".encode()).digest(), keys[i]))
    n_train = min(max(round(n * TRAIN_FRACTION[kind]), 1), n - 1)
    return {
        "train": tuple(sorted(names[i] for i in order[:n_train])),
        "eval": tuple(sorted(names[i] for i in order[n_train:])),
    }


def splits_digest(splits: dict[str, dict[str, Sequence[str]]]) -> str:
    """sha256 of the ``{kind: {split: [names]}}`` lists, as stored in ``asset_splits.json``."""
    canonical = {k: {s: list(v) for s, v in d.items()} for k, d in splits.items()}
    return hashlib.sha256(json.dumps(canonical, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def builtin_splits_document(seed: int = SPLITS_SEED) -> dict[str, Any]:
    """The content of ``asset_splits.json``: recomputed from the code's built-in pools."""
    splits = {kind: dict(split_pool(builtin_names(kind), kind, seed)) for kind in KINDS}  # type: ignore[arg-type]
    return {
        "generator": "scripts/make_asset_splits.py",
        "seed": seed,
        "train_fraction": dict(TRAIN_FRACTION),
        "counts": {k: {s: len(v) for s, v in d.items()} for k, d in splits.items()},
        "splits": {k: {s: list(v) for s, v in d.items()} for k, d in splits.items()},
        "sha256": splits_digest(splits),
    }


class AssetSplitsError(RuntimeError):
    """``asset_splits.json`` is missing, malformed, or was edited by hand."""


@functools.lru_cache(maxsize=1)
def _builtin_splits() -> dict[str, dict[str, tuple[str, ...]]]:
    regen = "regenerate it with `python scripts/make_asset_splits.py`"
    try:
        doc = json.loads(SPLITS_FILE.read_text(encoding="utf-8"))
        raw = doc["splits"]
        splits = {k: {s: tuple(raw[k][s]) for s in SPLITS} for k in KINDS}
        stored = doc["sha256"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise AssetSplitsError(f"cannot read built-in splits from {SPLITS_FILE} ({exc}); {regen}") from exc
    if splits_digest(splits) != stored:
        raise AssetSplitsError(
            f"{SPLITS_FILE} does not match its sha256 (edited by hand?); built-in splits must come from the "
            f"script: {regen}"
        )
    for kind, d in splits.items():
        if set(d["train"]) & set(d["eval"]):
            raise AssetSplitsError(f"{SPLITS_FILE}: {kind} train and eval overlap; {regen}")
    return splits


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
    return tuple(name for _, name in _folder_files(_check_kind(kind), folder))


def split_names(kind: AssetKind, split: Split, folder: str | Path | None = None, seed: int = 0) -> tuple[str, ...]:
    """Asset names of one split, sorted.

    Without ``folder`` the built-in split is read from ``asset_splits.json`` (for ``seed == 0``; another
    seed re-splits the built-in pool with the same function). With ``folder`` the same split function runs
    on the folder's files, keyed by their relative paths, so a copied folder splits identically anywhere.
    """
    kind = _check_kind(kind)
    split = _check_split(split)
    if folder is None:
        if seed == SPLITS_SEED:
            return _builtin_splits()[kind][split]
        return split_pool(builtin_names(kind), kind, seed)[split]
    files = _folder_files(kind, folder)
    return split_pool([n for _, n in files], kind, seed, keys=[r for r, _ in files])[split]
