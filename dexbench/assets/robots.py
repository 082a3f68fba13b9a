"""Resolve robot models (arms and hands) to MJCF files on disk.

* MuJoCo Menagerie robots go through the ``mujoco_menagerie`` package: downloaded on
  first use, or read from ``MENAGERIE_ROOT`` when that is set.
* Hands missing from Menagerie (``PINNED_SOURCES``) are downloaded from a pinned
  upstream archive, checked against a content digest and cached in
  ``hands_cache_dir()``.

Environment variables:

``MENAGERIE_ROOT``
    Folder holding Menagerie models as ``<name>/`` (read by ``mujoco_menagerie``).
``DEXBENCH_HANDS_ROOT``
    Folder holding pinned hands as ``<name>/``. When set it is the only place looked
    at, and it is trusted as is (no digest check) so that patched models can be tried.
``DEXBENCH_CACHE_DIR``
    Replaces ``platformdirs.user_cache_dir("dexbench")`` as dexbench's cache root;
    downloaded hands live in its ``hands/`` folder.
"""

from __future__ import annotations

import dataclasses
import gzip
import hashlib
import http.client
import os
import pathlib
import shutil
import tarfile
import tempfile
import urllib.error
import urllib.request
import zipfile
import zlib
from collections.abc import Iterator, Mapping
from typing import IO, Literal

import mujoco
import mujoco_menagerie
import platformdirs

HANDS_ROOT_ENV = "DEXBENCH_HANDS_ROOT"
CACHE_DIR_ENV = "DEXBENCH_CACHE_DIR"
MENAGERIE_ROOT_ENV = "MENAGERIE_ROOT"
DOWNLOAD_TIMEOUT_S = 60.0

# Menagerie robots dexbench builds embodiments from; any other Menagerie name works.
MENAGERIE_ROBOTS = (
    "franka_fr3",
    "universal_robots_ur10e",
    "ufactory_xarm7",
    "shadow_hand",
    "wonik_allegro",
    "leap_hand",
    "sharpa_wave",
)


class MissingRobotModelError(RuntimeError):
    """A robot model cannot be found or fetched; the message says what to set."""


class ChecksumMismatchError(RuntimeError):
    """A download is not the pinned content (or is unsafe); nothing was installed."""


@dataclasses.dataclass(frozen=True)
class PinnedSource:
    """An upstream archive holding a hand model, pinned by the files it must yield.

    ``sha256`` is ``tree_digest`` of the installed model folder, not a digest of the
    archive: GitHub regenerates ``archive/<commit>.tar.gz`` tarballs and their bytes
    (compression, timestamps) are not stable, while the files inside them are.

    ``members`` maps a path inside the archive (after dropping ``strip_components``
    leading components) to its path in the model folder. A key ending in ``/`` is a
    folder prefix, any other key one file; the rest of the archive is ignored.
    """

    name: str
    url: str
    archive_format: Literal["zip", "tar.gz"]
    members: Mapping[str, str]
    sha256: str
    strip_components: int = 0


_GRIPPERS = "robosuite/models/assets/grippers/"
PINNED_SOURCES: dict[str, PinnedSource] = {
    "inspire_hand": PinnedSource(
        name="inspire_hand",
        url="https://files.pythonhosted.org/packages/c8/54/"
        "3c0940c92d381eb5837cd29bf2c9fbf0a9dff313a2b2779e3902665276b3/"
        "robosuite-1.5.2-py3-none-any.whl",
        archive_format="zip",
        members={
            _GRIPPERS + "inspire_left_hand.xml": "inspire_left_hand.xml",
            _GRIPPERS + "inspire_right_hand.xml": "inspire_right_hand.xml",
            _GRIPPERS + "meshes/inspire_hands/": "meshes/inspire_hands/",
            "robosuite-1.5.2.dist-info/licenses/LICENSE": "LICENSE",
        },
        sha256="d5bac5ee45d50ae5817a8f64f48f394f92cfabe7fdd61515439e1206169a9831",
    ),
    "wuji_hand": PinnedSource(
        name="wuji_hand",
        url="https://github.com/wuji-technology/wuji-hand-description/archive/"
        "bbc2f64e.tar.gz",
        archive_format="tar.gz",
        members={p: p for p in ("mjcf/", "meshes/", "LICENSE", "README.md")},
        sha256="a6364fd2bde8e92c954278c33af752b7a1c1c7b3dd591ea1fe13e7618d5fde52",
        strip_components=1,
    ),
}


def robot_spec(collection: str, entry: str) -> mujoco.MjSpec:
    """Parse a robot model into an editable MjSpec.

    A spec rather than a compiled model, because embodiments are assembled by editing
    (attaching a hand to an arm, adding a floating wrist) before compiling.
    """
    return mujoco.MjSpec.from_file(str(robot_xml_path(collection, entry)))


def robot_xml_path(collection: str, entry: str) -> pathlib.Path:
    """The MJCF file of one model, fetching its collection on first use.

    ``entry`` is a Menagerie entry point name (``right_hand``, ``fr3``) for Menagerie
    robots and an XML path inside the model folder for ``PINNED_SOURCES`` hands.
    """
    if collection in PINNED_SOURCES:
        return _pinned_xml(PINNED_SOURCES[collection], entry)
    return _menagerie_xml(collection, entry)


def hands_cache_dir() -> pathlib.Path:
    """Where downloaded hands are cached: ``hands/`` under ``DEXBENCH_CACHE_DIR``.

    Falls back to the per-user cache dir; one function so that tests can move it.
    """
    root = os.environ.get(CACHE_DIR_ENV) or platformdirs.user_cache_dir("dexbench")
    return pathlib.Path(root) / "hands"


def tree_digest(folder: pathlib.Path) -> str:
    """Content digest of a folder, independent of timestamps and archive layout.

    sha256 over ``"<relative posix path>\\0<hex sha256 of the file>\\n"`` for every
    file under ``folder``, sorted by path.
    """
    folder = pathlib.Path(folder)
    digest = hashlib.sha256()
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        with path.open("rb") as f:
            file_sha = hashlib.file_digest(f, "sha256").hexdigest()
        digest.update(f"{path.relative_to(folder).as_posix()}\0{file_sha}\n".encode())
    return digest.hexdigest()


def _menagerie_xml(collection: str, entry: str) -> pathlib.Path:
    try:
        robot = mujoco_menagerie.get(collection)
    except mujoco_menagerie.UnknownRobotError as e:
        known = ", ".join([*MENAGERIE_ROBOTS, *PINNED_SOURCES])
        raise MissingRobotModelError(
            f"{e} Known robot collections: {known} (or any MuJoCo Menagerie name)."
        ) from None
    try:
        robot.entry(entry)  # no I/O: report a bad entry name before any download
    except mujoco_menagerie.UnknownEntryPointError as e:
        raise MissingRobotModelError(str(e)) from None
    hint = (
        f" To use an offline copy, set {MENAGERIE_ROOT_ENV} to a folder holding "
        f"{collection}/ in the mujoco-menagerie layout (e.g. the menagerie/ folder of "
        "an unpacked offline asset bundle); unset, models are downloaded on first use."
    )
    try:
        path = robot.xml(entry)
    except mujoco_menagerie.MenagerieError as e:
        raise MissingRobotModelError(
            f"cannot get {collection}/{entry}: {e}.{hint}"
        ) from e
    if not path.is_file():
        raise MissingRobotModelError(f"{collection}/{entry}: no {path}.{hint}")
    return path


def _pinned_xml(source: PinnedSource, entry: str) -> pathlib.Path:
    root = os.environ.get(HANDS_ROOT_ENV)
    fix = (
        f" Point {HANDS_ROOT_ENV} at a folder holding a complete {source.name}/, "
        f"or unset it to download the pinned copy from {source.url}."
    )
    if root:
        folder = pathlib.Path(root) / source.name
        if not folder.is_dir():
            raise MissingRobotModelError(
                f"{source.name} not found: {HANDS_ROOT_ENV}={root} has no "
                f"{source.name}/.{fix}"
            )
    else:
        folder = hands_cache_dir() / f"{source.name}-{source.sha256[:12]}"
        if not folder.is_dir():
            _install(source, folder)
    rel = pathlib.PurePosixPath(entry)
    if rel.is_absolute() or ".." in rel.parts or not (folder / rel).is_file():
        xmls = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*.xml"))
        raise MissingRobotModelError(
            f"{source.name} has no {entry!r} in {folder} "
            f"(XML files: {', '.join(xmls)}).{fix if root else ''}"
        )
    return folder / rel


def _install(source: PinnedSource, target: pathlib.Path) -> None:
    """Download, extract and verify in a staging folder next to ``target``, then rename.

    The rename is atomic, so ``target`` either holds verified files or does not exist.
    """
    target.parent.mkdir(parents=True, exist_ok=True)
    stage = pathlib.Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        archive, tree = stage / "archive", stage / "model"
        _download(source, archive)
        _extract(source, archive, tree)
        actual = tree_digest(tree)
        if actual != source.sha256:
            raise ChecksumMismatchError(
                f"{source.name} from {source.url}: content digest (tree_digest) is "
                f"{actual}, expected {source.sha256}; nothing was installed."
            )
        try:
            tree.rename(target)
        except OSError:
            if not target.is_dir():  # else another process installed it first
                raise
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _download(source: PinnedSource, dest: pathlib.Path) -> None:
    request = urllib.request.Request(source.url, headers={"User-Agent": "dexbench"})
    try:
        with (
            urllib.request.urlopen(request, timeout=DOWNLOAD_TIMEOUT_S) as response,
            dest.open("wb") as out,
        ):
            shutil.copyfileobj(response, out, 1 << 20)
    except (OSError, http.client.HTTPException) as e:
        if isinstance(e, urllib.error.HTTPError):
            e.close()  # an HTTP error keeps the response (and its socket) open
        raise MissingRobotModelError(
            f"could not download {source.name} from {source.url}: {e}. To work "
            f"offline, point {HANDS_ROOT_ENV} at a folder holding {source.name}/ "
            "(e.g. the hands/ folder of an unpacked offline asset bundle)."
        ) from e


def _extract(source: PinnedSource, archive: pathlib.Path, tree: pathlib.Path) -> None:
    """Write only the declared members into ``tree``.

    A declared member that is a link or whose name climbs out with ``..`` means the
    archive was tampered with: it is refused as a whole rather than filtered.
    """
    tree.mkdir()
    try:
        for name, data in _archive_entries(source, archive):
            rel = _destination(source, name)
            if rel is None:
                continue
            dest = tree / rel
            inside = dest.resolve().is_relative_to(tree.resolve())
            if data is None or ".." in rel.split("/") or not inside:
                raise ChecksumMismatchError(
                    f"{source.url}: member {name!r} is a link or leaves the model "
                    "folder; refusing the archive, nothing was installed."
                )
            dest.parent.mkdir(parents=True, exist_ok=True)
            with dest.open("wb") as out:
                shutil.copyfileobj(data, out)
    except (tarfile.TarError, zipfile.BadZipFile, gzip.BadGzipFile, *_CORRUPT) as e:
        raise ChecksumMismatchError(
            f"{source.url} is not a valid {source.archive_format} archive ({e}); "
            "nothing was installed."
        ) from e


_CORRUPT = (EOFError, zlib.error)  # truncated or damaged compressed streams


def _archive_entries(
    source: PinnedSource, archive: pathlib.Path
) -> Iterator[tuple[str, IO[bytes] | None]]:
    """(name, file) for every non-folder entry; file is None for links and the like."""
    if source.archive_format == "zip":
        with zipfile.ZipFile(archive) as zf:
            for info in zf.infolist():
                if not info.is_dir():
                    with zf.open(info) as f:
                        yield info.filename, f
    else:
        with tarfile.open(archive, "r:gz") as tf:
            for m in tf:
                if not m.isdir():
                    yield m.name, tf.extractfile(m) if m.isfile() else None


def _destination(source: PinnedSource, name: str) -> str | None:
    """Where an archive member goes in the model folder; None if not declared."""
    parts = [p for p in name.split("/") if p not in ("", ".")]
    rel = "/".join(parts[source.strip_components :])
    for prefix, dest in source.members.items():
        if prefix.endswith("/") and rel.startswith(prefix):
            return dest + rel[len(prefix) :]
        if rel == prefix:
            return dest
    return None
