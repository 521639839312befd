"""Texture and shape assets for Factor World scenes, with seeded, disjoint train/eval splits.

The default split holds whole families out (eval textures and shapes are unlike any in train, as the
paper's unseen images and scanned objects); the per-variant split stays available (``mode="variant"``).

Procedural families replace the web images and scanned objects of the original Factor World (nothing
can be downloaded here); Meta-World's own textures/meshes and users' folders go through the same names,
loaders and split function. See :mod:`lerobot_factorworld.assets.library` for the naming scheme.
"""

from .library import (
    ASSET_SPLITS,
    DEFAULT_ASSET_SPLIT,
    DEFAULT_FLOOR_TEXTURE,
    DEFAULT_TABLE_TEXTURE,
    KINDS,
    METAWORLD_MESH_FAMILIES,
    METAWORLD_MESHES,
    METAWORLD_TEXTURE_FAMILIES,
    METAWORLD_TEXTURES,
    SPLITS,
    TEXTURE_EXTENSIONS,
    TRAIN_FRACTION,
    VARIANTS_PER_FAMILY,
    AssetKind,
    AssetSplitMode,
    AssetSplitsError,
    Split,
    asset_families,
    asset_family,
    asset_kind,
    builtin_families,
    builtin_names,
    check_asset_split,
    clear_cache,
    folder_names,
    load_mesh,
    load_texture,
    metaworld_assets_dir,
    seen_families,
    split_names,
    split_pool,
    split_pool_by_family,
)
from .mesh import MAX_FACES, Mesh, normalize_mesh
from .mesh_io import MESH_EXTENSIONS, read_mesh_file, write_obj, write_stl
from .shapes import SHAPE_FAMILIES
from .textures import TEXTURE_FAMILIES

TEXTURE_KINDS = TEXTURE_FAMILIES
"""Alias: the procedural texture families."""
SHAPE_KINDS = SHAPE_FAMILIES
"""Alias: the procedural shape families."""

__all__ = [
    "ASSET_SPLITS",
    "DEFAULT_ASSET_SPLIT",
    "DEFAULT_FLOOR_TEXTURE",
    "DEFAULT_TABLE_TEXTURE",
    "KINDS",
    "MAX_FACES",
    "MESH_EXTENSIONS",
    "METAWORLD_MESHES",
    "METAWORLD_MESH_FAMILIES",
    "METAWORLD_TEXTURES",
    "METAWORLD_TEXTURE_FAMILIES",
    "SHAPE_FAMILIES",
    "SHAPE_KINDS",
    "SPLITS",
    "TEXTURE_EXTENSIONS",
    "TEXTURE_FAMILIES",
    "TEXTURE_KINDS",
    "TRAIN_FRACTION",
    "VARIANTS_PER_FAMILY",
    "AssetKind",
    "AssetSplitMode",
    "AssetSplitsError",
    "Mesh",
    "Split",
    "asset_families",
    "asset_family",
    "asset_kind",
    "builtin_families",
    "builtin_names",
    "check_asset_split",
    "clear_cache",
    "folder_names",
    "load_mesh",
    "load_texture",
    "metaworld_assets_dir",
    "normalize_mesh",
    "read_mesh_file",
    "seen_families",
    "split_names",
    "split_pool",
    "split_pool_by_family",
    "write_obj",
    "write_stl",
]
