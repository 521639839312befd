"""Texture and shape assets for Factor World scenes, with seeded, disjoint train/eval splits.

Procedural families replace the web images and scanned objects of the original Factor World (nothing
can be downloaded here); Meta-World's own textures/meshes and users' folders go through the same names,
loaders and split function. See :mod:`lerobot_factorworld.assets.library` for the naming scheme.
"""

from .library import (
    KINDS,
    METAWORLD_MESHES,
    METAWORLD_TEXTURES,
    SPLITS,
    TEXTURE_EXTENSIONS,
    TRAIN_FRACTION,
    VARIANTS_PER_FAMILY,
    AssetKind,
    AssetSplitsError,
    Split,
    asset_kind,
    builtin_names,
    clear_cache,
    folder_names,
    load_mesh,
    load_texture,
    metaworld_assets_dir,
    split_names,
    split_pool,
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
    "KINDS",
    "MAX_FACES",
    "MESH_EXTENSIONS",
    "METAWORLD_MESHES",
    "METAWORLD_TEXTURES",
    "SHAPE_FAMILIES",
    "SHAPE_KINDS",
    "SPLITS",
    "TEXTURE_EXTENSIONS",
    "TEXTURE_FAMILIES",
    "TEXTURE_KINDS",
    "TRAIN_FRACTION",
    "VARIANTS_PER_FAMILY",
    "AssetKind",
    "AssetSplitsError",
    "Mesh",
    "Split",
    "asset_kind",
    "builtin_names",
    "clear_cache",
    "folder_names",
    "load_mesh",
    "load_texture",
    "metaworld_assets_dir",
    "normalize_mesh",
    "read_mesh_file",
    "split_names",
    "split_pool",
    "write_obj",
    "write_stl",
]
