"""Writes that readers never see half done: temp file or folder, then one rename."""

from __future__ import annotations

import hashlib
import json
import os
import pathlib
import shutil


def write_json(path: pathlib.Path, obj) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(json.dumps(obj, indent=2) + "\n")
    os.replace(tmp, path)


def publish(build: pathlib.Path, dst: pathlib.Path, trash: pathlib.Path) -> None:
    """Move a finished folder `build` to `dst`; an older `dst` goes to `trash` first."""
    if dst.exists():
        shutil.rmtree(trash, ignore_errors=True)
        os.replace(dst, trash)
    dst.parent.mkdir(parents=True, exist_ok=True)
    os.replace(build, dst)
    shutil.rmtree(trash, ignore_errors=True)


def digests(root: pathlib.Path, skip: pathlib.Path) -> dict[str, str]:
    """sha256 of every file under `root` but `skip` (relative paths), to catch later
    damage that still parses (parquet pages carry no checksums)."""
    out = {}
    for path in sorted(p for p in root.rglob("*") if p.is_file()):
        rel = path.relative_to(root)
        if rel != skip:
            out[rel.as_posix()] = file_digest(path)
    return out


def file_digest(path: pathlib.Path) -> str:
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()
