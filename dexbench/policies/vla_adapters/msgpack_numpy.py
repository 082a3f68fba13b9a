"""msgpack with NumPy arrays, in the layout openpi's policy servers use on the wire.

An array travels as a map `{"__ndarray__": True, "data": raw bytes, "dtype": dtype.str,
"shape": [...]}`, a NumPy scalar as `{"__npgeneric__": True, "data": value, "dtype":
dtype.str}`; object, void and complex arrays are refused (msgpack has no safe form for
them, and pickling them would let a server run code on the client).
"""

from __future__ import annotations

from typing import Any

import msgpack
import numpy as np

_ARRAY, _SCALAR = "__ndarray__", "__npgeneric__"
_REFUSED_KINDS = ("O", "V", "c")


def _encode(obj: Any) -> Any:
    if isinstance(obj, np.ndarray | np.generic) and obj.dtype.kind in _REFUSED_KINDS:
        raise TypeError(f"cannot send a NumPy value of dtype {obj.dtype} over msgpack")
    if isinstance(obj, np.ndarray):
        data = np.ascontiguousarray(obj)
        return {_ARRAY: True, "data": data.tobytes(), "dtype": data.dtype.str,
                "shape": list(data.shape)}
    if isinstance(obj, np.generic):
        return {_SCALAR: True, "data": obj.item(), "dtype": obj.dtype.str}
    raise TypeError(f"cannot send a {type(obj).__name__} over msgpack")


def _decode(obj: dict) -> Any:
    keys = {k.decode() if isinstance(k, bytes) else k: v for k, v in obj.items()}
    if keys.get(_ARRAY):
        return np.frombuffer(keys["data"], dtype=np.dtype(keys["dtype"])).reshape(
            keys["shape"]).copy()
    if keys.get(_SCALAR):
        return np.dtype(keys["dtype"]).type(keys["data"])
    return obj


def packb(obj: Any) -> bytes:
    """Serialize `obj` (dicts, lists, str, numbers, NumPy arrays and scalars)."""
    return msgpack.packb(obj, default=_encode)


def unpackb(data: bytes) -> Any:
    """Deserialize what `packb` (or an openpi server) produced."""
    return msgpack.unpackb(data, object_hook=_decode)
