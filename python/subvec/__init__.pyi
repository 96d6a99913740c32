# Type stubs of the subvec package (python/src/module.cpp, python/subvec/__init__.py).
# Coordinates are image pixels: x right, y down, the image covers [0, width] x [0, height].
# Colors are RGB on the 0-255 scale.
from os import PathLike
from typing import Any, Literal, Sequence, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, PathLike[str]]
_Point = Sequence[float]   # (x, y)
_Color = Sequence[float]   # (r, g, b), 0-255
_Window = Sequence[float]  # (x0, y0, x1, y1)
_Rect = Sequence[float]    # (x, y, width, height)
_CSR = tuple[npt.NDArray[np.float64], npt.NDArray[np.int32], npt.NDArray[np.int32], tuple[int, int]]

class Error(Exception): ...
class InvalidArgumentError(Error, ValueError): ...
class InvalidMeshError(Error, ValueError): ...
class BadFileError(Error, ValueError): ...
class FileError(Error, OSError): ...
class LimitError(Error, ValueError): ...
class CancelledError(Error): ...

class LevelInfo(TypedDict):
    vertices: int
    triangles: int
    features: int
    tear_edges: int
    colors: int
    creases: int
    border_edges: int
    edges: int
    corners: int

class ObjectInfo(TypedDict):
    level: int
    name: str
    visible: bool
    vertices: int
    triangles: int
    features: int

class Info(TypedDict):
    width: int
    height: int
    levels: list[LevelInfo]
    objects: list[ObjectInfo]
    strokes: int
    metadata: dict[str, str]

class FeatureDict(TypedDict):
    id: int
    vertices: npt.NDArray[np.int32]
    saliency: float
    closed: bool

class Mesh(TypedDict):
    positions: npt.NDArray[np.float64]        # V x 2
    colors: npt.NDArray[np.float32]           # C x 3 (face-varying color values)
    triangles: npt.NDArray[np.int32]          # F x 3 vertex indices
    triangle_colors: npt.NDArray[np.int32]    # F x 3 color index of each corner
    creases: npt.NDArray[np.int32]            # E x 2 interior crease edges
    features: list[FeatureDict]               # tear chains

class Refined(TypedDict):
    positions: npt.NDArray[np.float32]        # N x 2
    colors: npt.NDArray[np.float32]           # M x 3
    triangles: npt.NDArray[np.int32]          # T x 3
    triangle_colors: npt.NDArray[np.int32]    # T x 3
    triangle_parent: npt.NDArray[np.int32]    # T
    position_stencils: Any                    # N x V scipy.sparse.csr_matrix, or _CSR
    color_stencils: Any                       # M x C scipy.sparse.csr_matrix, or _CSR

class Selection(TypedDict):
    colors: npt.NDArray[np.int32]
    seed_color: int
    seed_vertex: int

class StylizeReport(TypedDict):
    threshold: float
    in_region: int
    above: int
    chosen: int
    strokes: int

class Difference(TypedDict):
    mae: tuple[float, float, float]
    mae_mean: float
    psnr: float
    ssim: float

class VectorImage:
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def num_levels(self) -> int: ...
    @property
    def num_strokes(self) -> int: ...
    def copy(self) -> VectorImage: ...
    def render(self, *, width: int | None = None, scale: float | None = None,
               window: _Window | None = None, level: int = 0,
               overlay: Literal["none", "mesh", "features"] = "none", antialias: bool = True,
               threads: int = 0, depth: int = -1) -> npt.NDArray[np.uint8]:
        """H x W x 3 uint8 (x 4 when the window leaves the image); equals `subvec render`."""
    def save(self, path: _Path, *, lossless: bool = False) -> None: ...
    def to_bytes(self, *, format: Literal["svec", "json"] = "svec", lossless: bool = False) -> bytes: ...
    def info(self) -> Info: ...
    def mesh(self, *, level: int = 0) -> Mesh: ...
    def set_positions(self, positions: npt.ArrayLike, *, level: int = 0) -> None: ...
    def set_colors(self, colors: npt.ArrayLike, *, level: int = 0) -> None: ...
    def edit(self, ops: str | list[dict[str, Any]]) -> list[str]: ...
    def drag(self, from_: _Point, to: _Point, *, select: Literal["vertex", "feature"] = "vertex",
             sigma: float = 20.0, region: float = 0.0, level: int = 0, object: int | None = None) -> str: ...
    def move_feature(self, at: _Point, *, translate: _Point = (0, 0), rotate: float = 0.0,
                     region: float = 0.0, level: int = 0, object: int | None = None) -> str: ...
    def recolor(self, at: _Point | None, color: _Color, *, mode: Literal["blend", "transform"] = "blend",
                select: Literal["vertex", "feature", "region", "vertices", "all"] = "vertex",
                radius: float | None = None, tolerance: float | None = None,
                vertices: npt.ArrayLike | None = None,
                amount: float = 0.5, level: int = 0, object: int | None = None) -> str: ...
    def move_vertices(self, vertices: npt.ArrayLike, translate: _Point, *, region: float = 0.0,
                      level: int = 0, object: int | None = None) -> str: ...
    def add_feature(self, points: npt.ArrayLike, *, kind: Literal["tear", "crease"] = "tear",
                    level: int = 0) -> str:
        """A new tear (or crease) along the drawn polyline's C^2 fit; returns the log line."""
    def make_object(self, at: _Point | None = None, *, rect: tuple[int, int, int, int] | None = None,
                    name: str = "", level: int = 0) -> str:
        """Makes an object of the innermost closed tear around `at`, or of what `rect` (x, y, width,
        height) frames (its own mesh over a completed background); returns the log line."""
    def move_object(self, object: int, *, translate: _Point = (0, 0), rotate: float = 0,
                    scale: float = 1, pivot: _Point | None = None) -> str:
        """Scales, rotates (degrees, clockwise on screen) and moves an object rigidly about
        `pivot` (default: its centre); returns the log line."""
    def set_object_visible(self, object: int, visible: bool) -> str: ...
    def order_object(self, object: int, to: int) -> str:
        """Moves an object to position `to` of the drawing order (0 is the bottom)."""
    @property
    def objects(self) -> list[ObjectInfo]: ...
    def object_mesh(self, object: int) -> Mesh: ...
    def delete_feature(self, at: _Point, *, level: int = 0) -> str:
        """Deletes the feature nearest to `at`, joining its colors by a ramp; returns the log line."""
    def select_colors(self, at: _Point, *, select: Literal["vertex", "feature", "region"] = "vertex",
                      radius: float | None = None, tolerance: float | None = None,
                      level: int = 0) -> Selection: ...
    def blend_colors(self, colors: npt.ArrayLike, color: _Color, *, amount: float = 0.5,
                     level: int = 0) -> None: ...
    def transform_colors(self, colors: npt.ArrayLike, seed: _Color, color: _Color, *,
                         level: int = 0) -> tuple[float, float, float]: ...
    def deform(self, vertices: npt.ArrayLike, targets: npt.ArrayLike, *, region: float = 0.0,
               level: int = 0) -> float:
        """Moves the handle vertices to their targets (ARAP, never folding the mesh); returns how far
        they went: 1.0, or less where the mesh would fold (a crossing, the image frame)."""
    def stylize(self, *, level: int = 0, roi: _Rect | None = None, threshold: float | None = None,
                seed: int = 1, probability: float = 0.3) -> StylizeReport: ...
    def saliency(self, *, level: int = 0) -> npt.NDArray[np.float64]: ...
    @property
    def has_pyramid(self) -> bool: ...
    def filter(self, *, geometry_eta: Sequence[float] = (), color_eta: Sequence[float] = ()) -> VectorImage:
        """Every level filtered (eta per band, finest first); needs a pyramid (vectorize levels >= 2)."""
    def subdivide(self, *, level: int = 0, depth: int = 3, limit: bool = True,
                  sparse: Literal["scipy", "arrays"] = "scipy") -> Refined: ...

def vectorize(image: npt.ArrayLike, *, ratio: float = ..., vertices: int = ..., levels: int = ...,
              refine: int = ..., relocate: int = ..., l1_iterations: int = ..., threads: int = ...,
              max_memory: int = ...) -> VectorImage:
    """H x W x 3 uint8, or float32/float64 in [0, 1], to a vector image of the same size, with its
    levels of abstraction. Defaults and ranges are the library's (subvec::VectorizeOptions);
    max_memory (bytes, 0: the memory available) refuses an image whose estimated peak is larger."""
def load(path: _Path) -> VectorImage: ...
def from_bytes(data: bytes) -> VectorImage: ...
def read_image(path: _Path, *, max_pixels: int = ...) -> npt.NDArray[np.uint8]: ...
def write_png(path: _Path, image: npt.NDArray[np.uint8]) -> None: ...
def compare(reference: npt.ArrayLike, test: npt.ArrayLike) -> Difference: ...
def csr_matrix(pieces: _CSR) -> Any: ...
