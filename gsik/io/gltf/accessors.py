"""glTF accessors read into NumPy arrays, every offset and count checked against the buffer before it is viewed."""

from __future__ import annotations

import numpy as np

from gsik.errors import GltfError, show_value

#: Most elements one accessor may have.
MAX_COUNT = 16_000_000

COMPONENT_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32,
                    5126: np.float32}
TYPE_WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


def _integer(value, what: str, low: int = 0) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or value < low:
        raise GltfError(f"{what} must be an integer >= {low}, got {show_value(value)}")
    return value


def _item(items, index, what: str):
    """``items[index]``, refusing an index outside the array."""
    items = items or []
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(items):
        raise GltfError(f"{what} {show_value(index)} is not one of the file's {len(items)}")
    return items[index]


def read_accessor(document, buffers: tuple[bytes, ...], index: int, where: str) -> np.ndarray:
    """Accessor ``index`` as an array (count, width) (a SCALAR's width is 1), normalised integers as floats in [0, 1].

    Raises:
        GltfError: an unknown accessor, buffer view or buffer, a sparse accessor, or an accessor whose elements
            do not lie inside its buffer view and buffer.
    """
    acc = _item(document.accessors, index, f"{where}: accessor")
    what = f"{where}: accessors[{index}]"
    if acc.sparse is not None:
        raise GltfError(f"{what} is sparse; gsik reads plain accessors only")
    dtype = COMPONENT_DTYPES.get(acc.componentType)
    width = TYPE_WIDTHS.get(acc.type)
    if dtype is None or width is None:
        raise GltfError(f"{what}: component type {show_value(acc.componentType)} / type {show_value(acc.type)} "
                        f"is not a glTF accessor kind ({', '.join(TYPE_WIDTHS)})")
    count = _integer(acc.count, f"{what}.count", 1)
    if count > MAX_COUNT:
        raise GltfError(f"{what}.count is {count:,}; gsik reads at most {MAX_COUNT:,}")
    if acc.bufferView is None:
        return np.zeros((count, width), dtype=float if acc.normalized else dtype)
    view = _item(document.bufferViews, acc.bufferView, f"{what}: bufferView")
    data = _item(buffers, view.buffer, f"{what}: buffer")
    values = _view(data, view, acc, dtype, width, count, what)
    if acc.normalized and dtype != np.float32:
        return values.astype(float) / float(np.iinfo(dtype).max)
    return values


def _view(data: bytes, view, acc, dtype, width: int, count: int, what: str) -> np.ndarray:
    """The accessor's elements (count, width) copied out of ``data``, bounds checked first."""
    item = np.dtype(dtype).itemsize
    element = item * width
    view_offset = _integer(view.byteOffset or 0, f"{what}: its bufferView's byteOffset")
    view_length = _integer(view.byteLength, f"{what}: its bufferView's byteLength", 1)
    stride = _integer(view.byteStride or element, f"{what}: its bufferView's byteStride", 1)
    offset = _integer(acc.byteOffset or 0, f"{what}.byteOffset")
    if view_offset + view_length > len(data):
        raise GltfError(f"{what}: its bufferView ends at byte {view_offset + view_length:,}, past its buffer's "
                        f"{len(data):,} bytes")
    if stride < element or offset % item or stride % item:
        raise GltfError(f"{what}: byteStride {stride} / byteOffset {offset} do not fit elements of {element} bytes")
    end = offset + stride * (count - 1) + element
    if end > view_length:
        raise GltfError(f"{what}: {count:,} elements need {end:,} bytes of its bufferView, which has {view_length:,}")
    raw = np.frombuffer(data, dtype=np.uint8, count=end, offset=view_offset)
    rows = np.lib.stride_tricks.as_strided(raw[offset:], shape=(count, element), strides=(stride, 1))
    return np.ascontiguousarray(rows).view(dtype).reshape(count, width).copy()
