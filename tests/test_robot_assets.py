"""Tests for robot model resolution: offline copies, pinned downloads, error messages.

The model tests read the offline copies named by MENAGERIE_ROOT / DEXBENCH_HANDS_ROOT
and are skipped when those are unset. The download tests serve archives built here
from a local HTTP server, so nothing reaches the internet.
"""

from __future__ import annotations

import dataclasses
import http.server
import io
import os
import pathlib
import socket
import struct
import tarfile
import threading
import zipfile
from collections.abc import Iterator

import pytest

from dexbench.assets import robots

OFFLINE_HINT = 'run eval "$(bash <shared>/assets/unpack.sh)" or point it at a copy'

# (collection, entry, nq, nu); nu is None where only the joints are pinned down.
MODELS = [
    ("franka_fr3", "fr3", 7, None),
    ("universal_robots_ur10e", "ur10e", 6, None),
    ("ufactory_xarm7", "xarm7_nohand", 7, None),
    *[
        (hand, f"{side}_hand", nq, nu)
        for hand, nq, nu in [
            ("shadow_hand", 24, 20),
            ("wonik_allegro", 16, 16),
            ("leap_hand", 16, 16),
            ("sharpa_wave", 22, 22),
        ]
        for side in ("right", "left")
    ],
    *[("inspire_hand", f"inspire_{s}_hand.xml", 12, 12) for s in ("right", "left")],
    *[("wuji_hand", f"mjcf/{s}.xml", 20, 20) for s in ("right", "left")],
]


def _require_env(collection: str) -> None:
    var = (
        robots.HANDS_ROOT_ENV
        if collection in robots.PINNED_SOURCES
        else robots.MENAGERIE_ROOT_ENV
    )
    if not os.environ.get(var):
        pytest.skip(f"{var} is unset: {OFFLINE_HINT}")


@pytest.mark.parametrize(("collection", "entry", "nq", "nu"), MODELS)
def test_every_model_parses_and_compiles(
    collection: str, entry: str, nq: int, nu: int | None
) -> None:
    _require_env(collection)
    model = robots.robot_spec(collection, entry).compile()
    assert model.nq == nq
    if nu is not None:
        assert model.nu == nu


@pytest.mark.parametrize("name", sorted(robots.PINNED_SOURCES))
def test_pinned_digest_matches_offline_copy(name: str) -> None:
    """The offline copies are the pinned upstream files, so the digests must agree."""
    _require_env(name)
    folder = pathlib.Path(os.environ[robots.HANDS_ROOT_ENV]) / name
    assert robots.tree_digest(folder) == robots.PINNED_SOURCES[name].sha256


def test_tree_digest_depends_on_names_and_bytes_only(tmp_path: pathlib.Path) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    for folder, order in ((a, ["x/1.txt", "2.txt"]), (b, ["2.txt", "x/1.txt"])):
        for rel in order:
            (folder / rel).parent.mkdir(parents=True, exist_ok=True)
            (folder / rel).write_text(rel)
    os.utime(b / "2.txt", (0, 0))
    assert robots.tree_digest(a) == robots.tree_digest(b)
    (b / "2.txt").write_text("changed")
    assert robots.tree_digest(a) != robots.tree_digest(b)
    (b / "2.txt").write_text("2.txt")
    (b / "2.txt").rename(b / "3.txt")
    assert robots.tree_digest(a) != robots.tree_digest(b)


# --- pinned downloads, against archives served from 127.0.0.1 -----------------------

TOY_XML = b"""<mujoco model="toy_hand">
  <compiler meshdir="../meshes"/>
  <asset><mesh name="tet" file="tet.stl"/></asset>
  <worldbody>
    <body name="palm">
      <joint name="finger" type="hinge"/>
      <geom type="mesh" mesh="tet"/>
    </body>
  </worldbody>
  <actuator><position joint="finger"/></actuator>
</mujoco>
"""


def _tetrahedron_stl() -> bytes:
    v = [(0, 0, 0), (0.01, 0, 0), (0, 0.01, 0), (0, 0, 0.01)]
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    out = bytearray(b"toy".ljust(80, b"\0") + struct.pack("<I", len(faces)))
    for face in faces:
        out += struct.pack("<3f", 0, 0, 0)
        for i in face:
            out += struct.pack("<3f", *v[i])
        out += struct.pack("<H", 0)
    return bytes(out)


# What the installed model folder must hold, and the entry to load from it.
TOY_TREE = {
    "mjcf/toy.xml": TOY_XML,
    "meshes/tet.stl": _tetrahedron_stl(),
    "LICENSE": b"toy license\n",
}
TOY_ENTRY = "mjcf/toy.xml"

# Per format: archive member -> model path (None: present but not declared), the
# members mapping, and strip_components. Zip mimics a wheel, tar.gz a GitHub tarball.
LAYOUTS = {
    "tar.gz": (
        {
            "toy-abc123/mjcf/toy.xml": "mjcf/toy.xml",
            "toy-abc123/meshes/tet.stl": "meshes/tet.stl",
            "toy-abc123/LICENSE": "LICENSE",
            "toy-abc123/docs/ignored.md": None,
        },
        {"mjcf/": "mjcf/", "meshes/": "meshes/", "LICENSE": "LICENSE"},
        1,
    ),
    "zip": (
        {
            "toy/assets/toy.xml": "mjcf/toy.xml",
            "toy/assets/meshes/tet.stl": "meshes/tet.stl",
            "toy-1.0.dist-info/licenses/LICENSE": "LICENSE",
            "toy/ignored.py": None,
        },
        {
            "toy/assets/toy.xml": "mjcf/toy.xml",
            "toy/assets/meshes/": "meshes/",
            "toy-1.0.dist-info/licenses/LICENSE": "LICENSE",
        },
        0,
    ),
}


def _archive(
    fmt: str, files: dict[str, bytes], links: dict[str, str] | None = None
) -> bytes:
    buf = io.BytesIO()
    if fmt == "zip":
        with zipfile.ZipFile(buf, "w") as zf:
            for name, data in files.items():
                zf.writestr(name, data)
        return buf.getvalue()
    with tarfile.open(fileobj=buf, mode="w:gz") as tf:
        for name, data in files.items():
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tf.addfile(info, io.BytesIO(data))
        for name, target in (links or {}).items():
            info = tarfile.TarInfo(name)
            info.type, info.linkname = tarfile.SYMTYPE, target
            tf.addfile(info)
    return buf.getvalue()


def _toy_files(fmt: str) -> dict[str, bytes]:
    member_to_path = LAYOUTS[fmt][0]
    return {m: TOY_TREE.get(p, b"not declared") for m, p in member_to_path.items()}


class _Server:
    """A static HTTP server on 127.0.0.1 serving ``files`` (url path -> bytes)."""

    def __init__(self) -> None:
        files: dict[str, bytes] = {}

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self) -> None:
                body = files.get(self.path)
                self.send_response(200 if body is not None else 404)
                self.send_header("Content-Length", str(len(body or b"")))
                self.end_headers()
                self.wfile.write(body or b"")

            def log_message(self, *args: object) -> None:
                pass

        self.files = files
        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.thread = threading.Thread(
            target=self.httpd.serve_forever, args=(0.01,), daemon=True
        )
        self.thread.start()

    def url(self, path: str) -> str:
        return f"http://127.0.0.1:{self.httpd.server_address[1]}{path}"

    def stop(self) -> None:
        if self.thread.is_alive():
            self.httpd.shutdown()
            self.thread.join()
        self.httpd.server_close()


@pytest.fixture
def server() -> Iterator[_Server]:
    srv = _Server()
    yield srv
    srv.stop()


@pytest.fixture
def cache(tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> pathlib.Path:
    """No offline root, and the download cache inside tmp_path."""
    monkeypatch.delenv(robots.HANDS_ROOT_ENV, raising=False)
    monkeypatch.setenv(robots.CACHE_DIR_ENV, str(tmp_path / "cache"))
    assert robots.hands_cache_dir() == tmp_path / "cache" / "hands"
    return robots.hands_cache_dir()


@pytest.fixture
def expected_digest(tmp_path: pathlib.Path) -> str:
    folder = tmp_path / "expected"
    for rel, data in TOY_TREE.items():
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_bytes(data)
    return robots.tree_digest(folder)


def _pin(
    monkeypatch: pytest.MonkeyPatch, server: _Server, fmt: str, body: bytes, sha: str
) -> robots.PinnedSource:
    """Serve ``body`` and register it as the pinned source of ``toy_hand``."""
    path = f"/toy.{fmt}"
    server.files[path] = body
    _, members, strip = LAYOUTS[fmt]
    source = robots.PinnedSource(
        name="toy_hand",
        url=server.url(path),
        archive_format=fmt,  # type: ignore[arg-type]
        members=members,
        sha256=sha,
        strip_components=strip,
    )
    monkeypatch.setitem(robots.PINNED_SOURCES, "toy_hand", source)
    return source


def _all_files(folder: pathlib.Path) -> list[str]:
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*"))


@pytest.mark.parametrize("fmt", sorted(LAYOUTS))
def test_download_verifies_installs_then_uses_cache_offline(
    fmt: str,
    server: _Server,
    cache: pathlib.Path,
    expected_digest: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _pin(monkeypatch, server, fmt, _archive(fmt, _toy_files(fmt)), expected_digest)
    path = robots.robot_xml_path("toy_hand", TOY_ENTRY)
    folder = cache / f"toy_hand-{expected_digest[:12]}"
    assert path == folder / TOY_ENTRY
    assert os.listdir(cache) == [folder.name]  # no staging folder left behind
    assert _all_files(folder) == [
        "LICENSE",
        "meshes",
        "meshes/tet.stl",
        "mjcf",
        TOY_ENTRY,
    ]
    assert robots.tree_digest(folder) == expected_digest
    assert robots.robot_spec("toy_hand", TOY_ENTRY).compile().nu == 1

    server.stop()  # the second call must not need the network
    assert robots.robot_xml_path("toy_hand", TOY_ENTRY) == path
    assert robots.robot_spec("toy_hand", TOY_ENTRY).compile().nq == 1


@pytest.mark.parametrize("fmt", sorted(LAYOUTS))
def test_checksum_mismatch_installs_nothing(
    fmt: str,
    server: _Server,
    cache: pathlib.Path,
    expected_digest: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    files = _toy_files(fmt)
    license_member = next(m for m, p in LAYOUTS[fmt][0].items() if p == "LICENSE")
    files[license_member] = b"a different license\n"
    _pin(monkeypatch, server, fmt, _archive(fmt, files), expected_digest)
    with pytest.raises(robots.ChecksumMismatchError) as err:
        robots.robot_spec("toy_hand", TOY_ENTRY)
    assert expected_digest in str(err.value)
    assert "nothing was installed" in str(err.value)
    assert os.listdir(cache) == []


@pytest.mark.parametrize("fmt", sorted(LAYOUTS))
def test_path_traversal_member_is_rejected(
    fmt: str,
    server: _Server,
    cache: pathlib.Path,
    expected_digest: str,
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: pathlib.Path,
) -> None:
    member = next(m for m, p in LAYOUTS[fmt][0].items() if p == "meshes/tet.stl")
    evil = member.rsplit("/", 1)[0] + "/../../../../../evil.txt"
    files = {**_toy_files(fmt), evil: b"escaped"}
    _pin(monkeypatch, server, fmt, _archive(fmt, files), expected_digest)
    with pytest.raises(robots.ChecksumMismatchError, match="leaves the model folder"):
        robots.robot_xml_path("toy_hand", TOY_ENTRY)
    assert os.listdir(cache) == []
    assert not list(tmp_path.parent.rglob("evil.txt"))


def test_symlink_member_is_rejected(
    server: _Server,
    cache: pathlib.Path,
    expected_digest: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    body = _archive("tar.gz", _toy_files("tar.gz"), {"toy-abc123/mjcf/x": "/etc"})
    _pin(monkeypatch, server, "tar.gz", body, expected_digest)
    with pytest.raises(robots.ChecksumMismatchError, match="is a link"):
        robots.robot_xml_path("toy_hand", TOY_ENTRY)
    assert os.listdir(cache) == []


def test_corrupt_archive_installs_nothing(
    server: _Server,
    cache: pathlib.Path,
    expected_digest: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _pin(monkeypatch, server, "tar.gz", b"\x1f\x8b not really gzip", expected_digest)
    with pytest.raises(robots.ChecksumMismatchError, match=r"not a valid tar\.gz"):
        robots.robot_xml_path("toy_hand", TOY_ENTRY)
    assert os.listdir(cache) == []


def _closed_port_url() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    return f"http://127.0.0.1:{port}/toy.tar.gz"


@pytest.mark.parametrize("where", ["closed port", "HTTP 404"])
def test_unreachable_url_names_offline_variable(
    where: str,
    server: _Server,
    cache: pathlib.Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    source = _pin(monkeypatch, server, "tar.gz", b"", "0" * 64)
    url = _closed_port_url() if where == "closed port" else server.url("/missing")
    monkeypatch.setitem(
        robots.PINNED_SOURCES, "toy_hand", dataclasses.replace(source, url=url)
    )
    with pytest.raises(robots.MissingRobotModelError) as err:
        robots.robot_spec("toy_hand", TOY_ENTRY)
    assert robots.HANDS_ROOT_ENV in str(err.value)
    assert "toy_hand/" in str(err.value)
    assert os.listdir(cache) == []


# --- offline roots and names -------------------------------------------------------


def _no_network(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("must not download")

    monkeypatch.setattr(robots.urllib.request, "urlopen", refuse)


@pytest.mark.parametrize(
    ("collection", "entry"),
    [("inspire_hand", "inspire_right_hand.xml"), ("wuji_hand", "mjcf/left.xml")],
)
def test_missing_model_under_hands_root_names_the_variable(
    collection: str,
    entry: str,
    tmp_path: pathlib.Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _no_network(monkeypatch)
    monkeypatch.setenv(robots.HANDS_ROOT_ENV, str(tmp_path))
    with pytest.raises(robots.MissingRobotModelError, match=robots.HANDS_ROOT_ENV):
        robots.robot_spec(collection, entry)
    (tmp_path / collection).mkdir()  # the folder exists but the entry does not
    with pytest.raises(robots.MissingRobotModelError, match=robots.HANDS_ROOT_ENV):
        robots.robot_spec(collection, entry)


def test_missing_model_under_menagerie_root_names_the_variable(
    tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(robots.MENAGERIE_ROOT_ENV, str(tmp_path))
    with pytest.raises(robots.MissingRobotModelError, match=robots.MENAGERIE_ROOT_ENV):
        robots.robot_spec("shadow_hand", "right_hand")


def test_unknown_collection_lists_known_names() -> None:
    with pytest.raises(robots.MissingRobotModelError) as err:
        robots.robot_spec("no_such_robot", "right_hand")
    for name in [*robots.MENAGERIE_ROBOTS, "inspire_hand", "wuji_hand"]:
        assert name in str(err.value)


def test_unknown_menagerie_entry_lists_entries() -> None:
    with pytest.raises(robots.MissingRobotModelError, match="right_hand"):
        robots.robot_spec("shadow_hand", "middle_hand")
