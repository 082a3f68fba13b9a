"""JSON with NumPy arrays, in the layout of the `json-numpy` package that OpenVLA-OFT's
deploy server patches into its JSON handling.

An array or NumPy scalar travels as `{"__numpy__": base64 of its bytes (C order),
"dtype": its NumPy descr, e.g. "<f4", "shape": [...]}`; a scalar has shape `[]`.
These few lines stand in for the package so that a client needs no extra dependency
(and no global `json` patch); tests check them against `json_numpy` both ways.
"""

from __future__ import annotations

import base64
import json
from typing import Any

import numpy as np
from numpy.lib.format import descr_to_dtype, dtype_to_descr

_KEY = "__numpy__"


def _encode(obj: Any) -> dict:
    if isinstance(obj, np.ndarray | np.generic):
        data = np.ascontiguousarray(obj)
        return {_KEY: base64.b64encode(data.tobytes()).decode("ascii"),
                "dtype": dtype_to_descr(data.dtype), "shape": list(np.shape(obj))}
    raise TypeError(f"cannot send a {type(obj).__name__} as JSON")


def _decode(obj: dict) -> Any:
    if _KEY not in obj:
        return obj
    flat = np.frombuffer(base64.b64decode(obj[_KEY]), dtype=descr_to_dtype(obj["dtype"]))
    return flat.reshape(obj["shape"]).copy() if obj["shape"] else flat[0]


def dumps(obj: Any) -> str:
    return json.dumps(obj, default=_encode)


def loads(text: str | bytes) -> Any:
    return json.loads(text, object_hook=_decode)
