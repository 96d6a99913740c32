"""subvec: vector images built on piecewise smooth Loop subdivision surfaces.

A photograph becomes a coarse triangle mesh whose vertices carry positions and colors; Loop
subdivision turns it into a smooth color field with sharp tears. docs/python.md is the tour.

    import subvec
    photo = subvec.read_image("photo.png")          # H x W x 3 uint8
    image = subvec.vectorize(photo)                  # a VectorImage (levels included)
    image.recolor((120, 80), (40, 90, 200), radius=15)
    pixels = image.render(width=1024)                # H' x W' x 3 uint8
    image.save("photo.svec")

Errors raise subclasses of subvec.Error: InvalidArgumentError, InvalidMeshError, BadFileError,
LimitError (all also ValueError), FileError (also OSError) and CancelledError.
"""

from ._subvec import (  # noqa: F401  (the public API)
    BadFileError,
    CancelledError,
    Error,
    FileError,
    InvalidArgumentError,
    InvalidMeshError,
    LimitError,
    VectorImage,
    __version__,
    compare,
    from_bytes,
    load,
    read_image,
    vectorize,
    write_png,
)

__all__ = [
    "BadFileError",
    "CancelledError",
    "Error",
    "FileError",
    "InvalidArgumentError",
    "InvalidMeshError",
    "LimitError",
    "VectorImage",
    "compare",
    "csr_matrix",
    "from_bytes",
    "load",
    "read_image",
    "vectorize",
    "write_png",
]


def csr_matrix(pieces):
    """A (data, indices, indptr, shape) tuple as a scipy.sparse.csr_matrix.

    Returns the tuple unchanged when SciPy is not installed, so that callers without SciPy still
    get the CSR arrays (NumPy only)."""
    try:
        import scipy.sparse
    except ImportError:
        return pieces
    data, indices, indptr, shape = pieces
    return scipy.sparse.csr_matrix((data, indices, indptr), shape=shape)


def _subdivide(self, *, level=0, depth=3, limit=True, sparse="scipy"):
    """Refines one level `depth` times (pushed to the limit surface unless limit=False).

    Returns a dict: positions (N x 2 float32), colors (M x 3 float32), triangles and
    triangle_colors (T x 3 int32), triangle_parent (T int32: the control face each refines),
    position_stencils (N x V) and color_stencils (M x C), with positions ~= position_stencils @
    control positions. The stencils are scipy.sparse.csr_matrix when SciPy is importable and
    sparse="scipy" (the default); with sparse="arrays", or without SciPy, they are
    (data, indices, indptr, shape) tuples of NumPy arrays."""
    if sparse not in ("scipy", "arrays"):
        raise InvalidArgumentError(f"sparse must be 'scipy' or 'arrays', got {sparse!r}")
    out = self._subdivide(level=level, depth=depth, limit=limit)
    if sparse == "scipy":
        out["position_stencils"] = csr_matrix(out["position_stencils"])
        out["color_stencils"] = csr_matrix(out["color_stencils"])
    return out


VectorImage.subdivide = _subdivide
