"""Saving and loading disc networks as CSV, JSON and whitespace lists (geofrac.dfn3d.io)."""

import json
import os

import numpy as np
import pytest

from geofrac.dfn.errors import DfnError
from geofrac.dfn3d import io as dio
from geofrac.dfn3d.io import load_discs, save_discs
from geofrac.dfn3d.network import DiscNetwork
from geofrac.dfn3d.sampling import DiscSet, sample_network

HEADER = "x,y,z,nx,ny,nz,radius,set"
BOX = (0.0, 0.0, 0.0, 10.0, 10.0, 10.0)


@pytest.fixture(scope="module")
def network() -> DiscNetwork:
    sets = [
        DiscSet("set1", 30.0, 60.0, 20.0, 0.5, 4.0, 2.5, count=40),
        DiscSet("set 2", 120.0, 0.0, 5.0, 1.0, 1.0, 1.0, count=30),  # horizontal poles
    ]
    return sample_network(sets, box=BOX, seed=12)


def awkward() -> DiscNetwork:
    """Floats that a short decimal format would round, and a set listed before its use."""
    n = np.array([[0.6, 0.0, 0.8], [0.0, 1.0, 0.0]])
    return DiscNetwork(
        centre=np.array([[0.1 + 0.2, 1.0 / 3.0, -1e-300], [1e300, -0.0, 5e-324]]),
        normal=n / np.linalg.norm(n, axis=1)[:, None],
        radius=np.array([2.0**0.5, 1e-200]),
        set_index=np.array([1, 0]),
        set_names=("b", "a"),
    )


def same_geometry(a: DiscNetwork, b: DiscNetwork) -> None:
    for field in ("centre", "normal", "radius"):
        assert getattr(a, field).tobytes() == getattr(b, field).tobytes(), field


def set_of_each(net: DiscNetwork) -> list[str]:
    return [net.set_names[i] for i in net.set_index]


@pytest.mark.parametrize("suffix", [".csv", ".json"])
def test_round_trip_is_exact(tmp_path, network, suffix):
    path = tmp_path / f"net{suffix}"
    save_discs(network, path)
    back = load_discs(path)
    same_geometry(back, network)
    assert back.set_index.tolist() == network.set_index.tolist()
    assert back.set_names == network.set_names


@pytest.mark.parametrize("suffix", [".dat", ".txt", ".DAT"])
def test_round_trip_of_the_list_format_keeps_geometry(tmp_path, network, suffix):
    path = tmp_path / f"net{suffix}"
    save_discs(network, str(path))
    back = load_discs(str(path))
    same_geometry(back, network)
    assert back.set_names == ("file",) and set(back.set_index.tolist()) == {0}


@pytest.mark.parametrize("suffix", [".csv", ".json", ".dat"])
def test_round_trip_of_awkward_floats(tmp_path, suffix):
    path = tmp_path / f"odd{suffix}"
    save_discs(awkward(), path)
    back = load_discs(path)
    same_geometry(back, awkward())
    if suffix == ".csv":  # names numbered as first seen
        assert back.set_names == ("a", "b") and set_of_each(back) == ["a", "b"]
    if suffix == ".json":  # the "sets" list keeps the order
        assert back.set_names == ("b", "a") and set_of_each(back) == ["a", "b"]


def test_saving_writes_only_the_given_path(tmp_path, network):
    for suffix in (".csv", ".json", ".dat"):
        save_discs(network, tmp_path / f"only{suffix}")
    assert sorted(os.listdir(tmp_path)) == ["only.csv", "only.dat", "only.json"]


def test_empty_network_round_trips(tmp_path):
    empty = DiscNetwork(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0, int), ())
    for suffix in (".csv", ".json", ".dat"):
        save_discs(empty, tmp_path / f"e{suffix}")
        assert load_discs(tmp_path / f"e{suffix}").size == 0


def test_layouts(tmp_path):
    save_discs(awkward(), tmp_path / "n.csv")
    lines = (tmp_path / "n.csv").read_text().splitlines()
    assert lines[0] == HEADER
    assert lines[1] == f"{0.1 + 0.2!r},{1.0 / 3.0!r},-1e-300,0.6,0.0,0.8,{2.0**0.5!r},a"
    save_discs(awkward(), tmp_path / "n.json")
    data = json.loads((tmp_path / "n.json").read_text())
    assert data["sets"] == ["b", "a"]
    assert data["fractures"][1] == {
        "centre": [1e300, -0.0, 5e-324],
        "normal": [0.0, 1.0, 0.0],
        "radius": 1e-200,
        "set": "b",
    }
    save_discs(awkward(), tmp_path / "n.txt")
    lines = (tmp_path / "n.txt").read_text().splitlines()
    assert lines[0].startswith("#") and lines[2].split()[3:] == ["0.0", "1.0", "0.0", "1e-200"]


def test_hand_written_files(tmp_path):
    # dfnWorks/FracMan-style list: comments, tabs, non-unit and downward normals
    (tmp_path / "h.dat").write_text(
        "# x y z nx ny nz r\n\n1 2 3   0 0 -2  0.5  # a comment\n\t4\t5\t6\t3\t4\t0\t1e0\n"
    )
    net = load_discs(tmp_path / "h.dat")
    assert net.centre.tolist() == [[1, 2, 3], [4, 5, 6]]
    np.testing.assert_allclose(net.normal, [[0, 0, 1], [0.6, 0.8, 0]], atol=1e-16)
    assert net.radius.tolist() == [0.5, 1.0]
    # CSV without the set column, spaces around fields
    (tmp_path / "h.csv").write_text("x, y, z, nx, ny, nz, radius\n0,0,0, 1,0,0, 2\n")
    net = load_discs(tmp_path / "h.csv")
    assert net.set_names == ("file",) and net.normal.tolist() == [[1, 0, 0]]
    # JSON without set names
    (tmp_path / "h.json").write_text(
        json.dumps({"fractures": [{"centre": [0, 0, 0], "normal": [0, 0, 3], "radius": 1}]})
    )
    net = load_discs(tmp_path / "h.json")
    assert net.set_names == ("file",) and net.normal.tolist() == [[0, 0, 1]]


def test_unknown_suffix_and_unreadable_files(tmp_path, network):
    with pytest.raises(DfnError, match=r"n.xyz: unknown disc file type '.xyz'"):
        save_discs(network, tmp_path / "n.xyz")
    with pytest.raises(DfnError, match="unknown disc file type"):
        load_discs(tmp_path / "n.xyz")
    with pytest.raises(DfnError, match=r"missing.csv: cannot read \(no such file\)"):
        load_discs(tmp_path / "missing.csv")
    (tmp_path / "dir.csv").mkdir()
    with pytest.raises(DfnError, match=r"dir.csv: cannot read \(not a regular file\)"):
        load_discs(tmp_path / "dir.csv")
    (tmp_path / "bin.csv").write_bytes(b"\xff\xfe\x00x")
    with pytest.raises(DfnError, match=r"bin.csv: cannot read, not UTF-8"):
        load_discs(tmp_path / "bin.csv")
    with pytest.raises(DfnError, match="cannot write"):
        save_discs(network, tmp_path / "no" / "such" / "dir.csv")


def test_large_files_are_refused(tmp_path, monkeypatch):
    big = tmp_path / "big.dat"
    with big.open("wb") as f:  # sparse: no 50 MB written
        f.truncate(dio.MAX_FILE_BYTES + 1)
    with pytest.raises(DfnError, match=r"big.dat: file too large \(50000001 bytes\).*50 MB"):
        load_discs(big)
    monkeypatch.setattr(dio, "MAX_FILE_BYTES", 10)
    (tmp_path / "small.dat").write_text("0 0 0 0 0 1 1\n")
    with pytest.raises(DfnError, match=r"small.dat: file too large"):
        load_discs(tmp_path / "small.dat")


CSV_ERRORS = [
    ("", "empty file"),
    ("\n \n", "empty file"),
    ("0,0,0,0,0,1,1,a\n", r"line 1: expected the header 'x,y,z,nx,ny,nz,radius,set'"),
    ("x,y,z,nx,ny,nz,r\n", "line 1: expected the header"),
    (f"{HEADER}\n0,0,0,0,0,1,1,a\n0,0,0,0,0,1,1\n", "line 3: expected 8 columns, got 7"),
    (f"{HEADER}\n\n0,0,0,0,0,1,1,a,b\n", "line 3: expected 8 columns, got 9"),
    (f"{HEADER}\n0,zero,0,0,0,1,1,a\n", "line 2: y = 'zero' is not a number"),
    (f"{HEADER}\n0,0,,0,0,1,1,a\n", "line 2: z = '' is not a number"),
    (f"{HEADER}\n0,0,0,0,0,1,inf,a\n", "line 2: radius = 'inf' is not finite"),
    (f"{HEADER}\nnan,0,0,0,0,1,1,a\n", "line 2: x = 'nan' is not finite"),
    (f"{HEADER}\n0,0,0,0,0,1e400,1,a\n", "line 2: nz = '1e400' is not finite"),
    (f"{HEADER}\n0,0,0,0,0,0,1,a\n", r"line 2: zero normal \(nx = ny = nz = 0\)"),
    (f"{HEADER}\n0,0,0,0,0,1,0,a\n", "line 2: radius = '0' must be > 0"),
    (f"{HEADER}\n0,0,0,0,0,1,-2,a\n", "line 2: radius = '-2' must be > 0"),
    (f"{HEADER}\n0,0,0,0,0,1,1,\n", "line 2: set name must be a non-empty string"),
    (f'{HEADER}\n0,0,0,0,0,1,1,"a"\n', "line 2: set name '\"a\"' must not contain"),
]


@pytest.mark.parametrize(("text", "match"), CSV_ERRORS)
def test_csv_errors(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(DfnError, match=match) as info:
        load_discs(path)
    assert str(info.value).startswith(f"{path}: ")


LIST_ERRORS = [
    ("# only a comment\n   \n", "no error"),
    ("", "empty file"),
    ("0 0 0 0 0 1\n", "line 1: expected 7 columns .*, got 6"),
    ("# c\n0 0 0 0 0 1 1 8\n", "line 2: expected 7 columns .*, got 8"),
    ("0,0,0,0,0,1,1\n", "line 1: expected 7 columns .*, got 1"),
    ("0 0 0 0 0 1 1\n0 0 0 0 0 0 1\n", "line 2: zero normal"),
    ("0 0 0 0 0 1 -1\n", "line 1: radius = '-1' must be > 0"),
    ("0 0 0 0 0 1 nan\n", "line 1: radius = 'nan' is not finite"),
    ("0 0 x 0 0 1 1\n", "line 1: z = 'x' is not a number"),
]


@pytest.mark.parametrize(("text", "match"), LIST_ERRORS)
def test_list_errors(tmp_path, text, match):
    path = tmp_path / "bad.dat"
    path.write_text(text)
    if match == "no error":  # comments only: a valid file without discs
        assert load_discs(path).size == 0
        return
    with pytest.raises(DfnError, match=match) as info:
        load_discs(path)
    assert str(info.value).startswith(f"{path}: ")


def disc(**changes) -> dict:
    entry = {"centre": [0, 0, 0], "normal": [0, 0, 1], "radius": 1.0, "set": "a"}
    entry.update(changes)
    return {k: v for k, v in entry.items() if v is not None}


JSON_ERRORS = [
    ("", "empty file"),
    ('{"fractures": [', "malformed JSON at line 1, column"),
    ('{"fractures": [{"radius": ' + "1" * 5000 + "}]}", "malformed JSON"),
    ("[" * 100_000 + "]" * 100_000, "malformed JSON"),
    ("[1, 2]", "expected a JSON object, got list"),
    ({"discs": []}, "'fractures' must be a list of discs, got NoneType"),
    ({"fractures": [disc(), 5]}, r"fractures\[1\]: expected an object"),
    ({"fractures": [disc(colour="red")]}, r"fractures\[0\]: unknown keys \['colour'\]"),
    ({"fractures": [disc(radius=None)]}, r"fractures\[0\]: missing 'radius'"),
    ({"fractures": [disc(centre=None)]}, r"fractures\[0\]: 'centre' must be a list of 3 numbers"),
    ({"fractures": [disc(normal=[0, 1])]}, r"fractures\[0\]: 'normal' must be a list of 3"),
    ({"fractures": [disc(centre=[0, "1", 0])]}, r"fractures\[0\]: y = '1' is not a number"),
    ({"fractures": [disc(normal=[0, True, 0])]}, r"fractures\[0\]: ny = True is not a number"),
    ({"fractures": [disc(normal=[0, 0, 0])]}, r"fractures\[0\]: zero normal"),
    ({"fractures": [disc(), disc(radius=0)]}, r"fractures\[1\]: radius = 0 must be > 0"),
    ({"fractures": [disc(set="")]}, r"fractures\[0\]: set name must be a non-empty string"),
    ({"fractures": [disc(set=3)]}, r"fractures\[0\]: set name must be a non-empty string"),
    ({"sets": "a", "fractures": []}, "'sets' must be a list of set names"),
    ({"sets": ["a", "a"], "fractures": []}, "set names in 'sets' must be distinct"),
    ({"sets": ["b"], "fractures": [disc()]}, r"fractures\[0\]: set 'a' is not in 'sets'"),
    (
        '{"fractures": [{"centre": [NaN, 0, 0], "normal": [0, 0, 1], "radius": 1}]}',
        r"fractures\[0\]: x = nan is not finite",
    ),
    (
        '{"fractures": [{"centre": [0, 0, 0], "normal": [0, 0, 1], "radius": 1e999}]}',
        r"fractures\[0\]: radius = inf is not finite",
    ),
]


@pytest.mark.parametrize(("content", "match"), JSON_ERRORS)
def test_json_errors(tmp_path, content, match):
    path = tmp_path / "bad.json"
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    with pytest.raises(DfnError, match=match) as info:
        load_discs(path)
    assert str(info.value).startswith(f"{path}: ")


def test_near_unit_normals_are_kept_and_others_normalised(tmp_path):
    n = [0.6, 0.0, 0.8 + 2e-16]  # within 1e-14 of unit length: kept as written
    path = tmp_path / "n.json"
    path.write_text(
        json.dumps(
            {"fractures": [disc(normal=n), disc(normal=[0, 0, -5.0]), disc(normal=[-1, 0, 0])]}
        )
    )
    net = load_discs(path)
    assert net.normal.tolist() == [n, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
    # huge and tiny normals are scaled before they are normalised (no overflow)
    path.write_text(
        json.dumps(
            {"fractures": [disc(normal=[3e300, 4e300, 0]), disc(normal=[0, -3e-310, 4e-310])]}
        )
    )
    np.testing.assert_allclose(load_discs(path).normal, [[0.6, 0.8, 0], [0, -0.6, 0.8]], atol=1e-15)
