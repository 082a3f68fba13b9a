"""msgpack with NumPy arrays, in the layout of openpi's `openpi_client.msgpack_numpy`.

An array travels as a map `{b"__ndarray__": True, b"data": raw bytes (C order), b"dtype":
dtype.str, b"shape": [...]}`, a NumPy scalar as `{b"__npgeneric__": True, b"data":
value, b"dtype": dtype.str}`. The keys are msgpack *bytes*, not strings: openpi's decoder
looks only for bytes keys and passes anything else on as a plain dict. Object, void and
complex values are refused, as openpi refuses them (msgpack has no safe form for them,
and pickling them would let a server run code on the client).

openpi-client itself is not imported: it declares numpy<2 and LeRobot needs numpy>=2, so
it cannot be a dependency; tests check this module against it in both directions.
"""

from __future__ import annotations

from typing import Any

import msgpack
import numpy as np

_ARRAY, _SCALAR = b"__ndarray__", b"__npgeneric__"
_DATA, _DTYPE, _SHAPE = b"data", b"dtype", b"shape"
_REFUSED_KINDS = ("O", "V", "c")


def _encode(obj: Any) -> Any:
    if isinstance(obj, np.ndarray | np.generic) and obj.dtype.kind in _REFUSED_KINDS:
        raise TypeError(f"cannot send a NumPy value of dtype {obj.dtype} over msgpack")
    if isinstance(obj, np.ndarray):
        data = np.ascontiguousarray(obj)
        return {_ARRAY: True, _DATA: data.tobytes(), _DTYPE: data.dtype.str,
                _SHAPE: list(data.shape)}
    if isinstance(obj, np.generic):
        return {_SCALAR: True, _DATA: obj.item(), _DTYPE: obj.dtype.str}
    raise TypeError(f"cannot send a {type(obj).__name__} over msgpack")


def _decode(obj: dict) -> Any:
    if _ARRAY in obj:
        return np.frombuffer(obj[_DATA], dtype=np.dtype(obj[_DTYPE])).reshape(
            obj[_SHAPE]).copy()
    if _SCALAR in obj:
        return np.dtype(obj[_DTYPE]).type(obj[_DATA])
    return obj


def packb(obj: Any) -> bytes:
    """Serialize `obj` (dicts, lists, str, numbers, NumPy arrays and scalars)."""
    return msgpack.packb(obj, default=_encode)


def unpackb(data: bytes) -> Any:
    """Deserialize what `packb` or an openpi server (`openpi_client.msgpack_numpy`) packed."""
    return msgpack.unpackb(data, object_hook=_decode)
