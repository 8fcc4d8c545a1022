"""Saving and loading networks as CSV and JSON (geofrac.dfn.io)."""

import json

import numpy as np
import pytest

from geofrac.dfn.errors import DfnError
from geofrac.dfn.io import load_network, save_network
from geofrac.dfn.polygon import rectangle
from geofrac.dfn.sampling import FractureSet, Network, generate_network

HEADER = "set,x0,y0,x1,y1"


@pytest.fixture(scope="module")
def network() -> Network:
    sets = [
        FractureSet("set1", 47.473, 7.79, 10.0, 50.0, 3.1, count=200),
        FractureSet("set 2", 102.753, 7.56, 10.0, 50.0, 3.1, distribution="normal", count=150),
        FractureSet("set-3", 162.83, 12.0, 10.0, 50.0, 3.1, distribution="von_mises", count=50),
    ]
    return generate_network(sets, rectangle((0.0, 0.0), (200.0, 100.0)), seed=12)


def awkward() -> Network:
    """Floats that a short decimal format would round: 0.1 + 0.2, 1/3, tiny and huge."""
    segs = np.array(
        [
            [[0.1 + 0.2, 1.0 / 3.0], [-1e-300, 2.0**0.5]],
            [[1e300, -0.0], [1e300 * (1 + 2**-52), 5e-324]],
        ]
    )
    return Network(segs, np.array([1, 0]), ("b", "a"))


def assert_same(a: Network, b: Network) -> None:
    # bit for bit, including the sign of zeros
    assert a.segments.tobytes() == b.segments.tobytes()
    assert np.array_equal(a.set_index, b.set_index)
    assert a.set_names == b.set_names


def fracture_sets(net: Network) -> list[str]:
    return [net.set_names[i] for i in net.set_index]


@pytest.mark.parametrize("suffix", [".csv", ".json"])
def test_round_trip_is_exact(tmp_path, network, suffix):
    path = tmp_path / f"net{suffix}"
    save_network(network, path)
    assert_same(load_network(path), network)


@pytest.mark.parametrize("suffix", [".csv", ".json"])
def test_round_trip_of_awkward_floats(tmp_path, suffix):
    path = tmp_path / f"odd{suffix}"
    net = awkward()
    save_network(net, str(path))
    back = load_network(str(path))
    assert back.segments.tobytes() == net.segments.tobytes()
    assert fracture_sets(back) == fracture_sets(net) == ["a", "b"]
    # "a" is set 1 but the first name in the CSV file, so CSV numbers the sets anew
    assert back.set_names == (("a", "b") if suffix == ".csv" else ("b", "a"))


def test_csv_layout(tmp_path):
    path = tmp_path / "n.csv"
    save_network(awkward(), path)
    lines = path.read_text().splitlines()
    assert lines[0] == HEADER
    assert lines[1] == f"a,{0.1 + 0.2!r},{1.0 / 3.0!r},-1e-300,{2.0**0.5!r}"
    assert len(lines) == 3


def test_json_layout(tmp_path):
    path = tmp_path / "n.json"
    save_network(awkward(), path)
    data = json.loads(path.read_text())
    assert data["format"] == "geofrac-dfn" and data["version"] == 1
    assert data["sets"] == ["b", "a"]
    assert data["fractures"][0] == [1, 0.1 + 0.2, 1.0 / 3.0, -1e-300, 2.0**0.5]


def test_csv_sets_in_order_of_first_appearance(tmp_path):
    path = tmp_path / "hand.csv"
    path.write_text(f"{HEADER}\nzeta,0,0,1,1\n\nalpha, 1, 1, 2, 2\nzeta,0,1,1,0\n")
    net = load_network(path)
    assert net.set_names == ("zeta", "alpha")
    assert net.set_index.tolist() == [0, 1, 0]
    assert net.segments[1].tolist() == [[1, 1], [2, 2]]


def test_json_keeps_empty_sets(tmp_path):
    net = Network(np.array([[[0.0, 0.0], [1.0, 0.0]]]), np.array([1]), ("empty", "full"))
    save_network(net, tmp_path / "n.json")
    assert_same(load_network(tmp_path / "n.json"), net)
    # an empty network round-trips too
    empty = Network(np.zeros((0, 2, 2)), np.zeros(0, dtype=int), ("a",))
    save_network(empty, tmp_path / "e.json")
    assert_same(load_network(tmp_path / "e.json"), empty)


def test_unknown_suffix(tmp_path, network):
    with pytest.raises(DfnError, match=r"unknown network file type '\.txt'"):
        save_network(network, tmp_path / "n.txt")
    (tmp_path / "n.txt").write_text("x")
    with pytest.raises(DfnError, match=r"n\.txt: unknown network file type"):
        load_network(tmp_path / "n.txt")


def test_unreadable_files(tmp_path):
    with pytest.raises(DfnError, match=r"missing\.csv: cannot read"):
        load_network(tmp_path / "missing.csv")
    (tmp_path / "dir.json").mkdir()
    with pytest.raises(DfnError, match=r"dir\.json: cannot read"):
        load_network(tmp_path / "dir.json")
    (tmp_path / "bin.csv").write_bytes(b"set,x0,y0,x1,y1\n\xff\xfe,1,2,3,4\n")
    with pytest.raises(DfnError, match=r"bin\.csv: cannot read, not UTF-8"):
        load_network(tmp_path / "bin.csv")


def test_unwritable_file(tmp_path, network):
    with pytest.raises(DfnError, match="cannot write"):
        save_network(network, tmp_path / "no" / "such" / "dir.csv")


CSV_ERRORS = [
    ("", "empty file"),
    ("\n  \n", "empty file"),
    ("a,0,0,1,1\n", r"line 1: expected the header 'set,x0,y0,x1,y1', got 'a,0,0,1,1'"),
    ("set,x,y,x1,y1\na,0,0,1,1\n", "line 1: expected the header"),
    (f"{HEADER}\na,0,0,1,1\nb,0,0,1\n", "line 3: expected 5 columns, got 4"),
    (f"{HEADER}\na,0,0,1,1,7\n", "line 2: expected 5 columns, got 6"),
    (f"{HEADER}\na,0,zero,1,1\n", "line 2: y0 = 'zero' is not a number"),
    (f"{HEADER}\na,0,0,,1\n", "line 2: x1 = '' is not a number"),
    (f"{HEADER}\na,0,0,1,inf\n", "line 2: y1 = 'inf' is not finite"),
    (f"{HEADER}\na,nan,0,1,1\n", "line 2: x0 = 'nan' is not finite"),
    (
        f"{HEADER}\na,0,0,1,1\n\na,2,3,2,3.0\n",
        r"line 4: zero-length fracture, both endpoints at \(2",
    ),
    (f"{HEADER}\n ,0,0,1,1\n", "line 2: empty set name"),
    (f'{HEADER}\n"a",0,0,1,1\n', "set name '\"a\"' must not contain"),
]


@pytest.mark.parametrize(("text", "match"), CSV_ERRORS)
def test_csv_errors(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(DfnError, match=match) as info:
        load_network(path)
    assert str(path) in str(info.value)


def good_json(**changes) -> dict:
    data = {
        "format": "geofrac-dfn",
        "version": 1,
        "sets": ["a", "b"],
        "fractures": [[0, 0.0, 0.0, 1.0, 1.0], [1, 2.0, 0.0, 2.0, 1.0]],
    }
    data.update(changes)
    return data


JSON_HEAD = '{"format": "geofrac-dfn", "version": 1, "sets": ["a"], '  # + "fractures"
JSON_ERRORS = [
    ("", "empty file"),
    ('{"format": "geofrac-dfn", "version": 1,', "malformed JSON at line 1, column"),
    ("[1, 2]", "expected a JSON object, got list"),
    (good_json(format="other"), "unknown format 'other'"),
    ({k: v for k, v in good_json().items() if k != "format"}, "unknown format None"),
    (good_json(version=2), "unsupported version 2, expected 1"),
    (good_json(version=True), "unsupported version True"),
    ({k: v for k, v in good_json().items() if k != "version"}, "unsupported version None"),
    (good_json(sets="a"), "'sets' must be a list of set names"),
    (good_json(sets=["a", 1]), "'sets' must be a list of set names"),
    (good_json(sets=["a", "a"]), "set names must be distinct"),
    (good_json(sets=["a", "b,c"]), "must not contain commas"),
    (good_json(fractures={"0": 1}), "'fractures' must be a list, got dict"),
    (good_json(fractures=[[0, 0, 0, 1, 1], [0, 0, 0, 1]]), r"fractures\[1\]: expected \[set_index"),
    (good_json(fractures=[[0, 0, 0, 1, 1], 5]), r"fractures\[1\]: expected \[set_index"),
    (good_json(fractures=[[2, 0, 0, 1, 1]]), r"fractures\[0\]: set index 2 out of range, 2 sets"),
    (good_json(fractures=[[-1, 0, 0, 1, 1]]), r"fractures\[0\]: set index -1 out of range"),
    (good_json(fractures=[[0.0, 0, 0, 1, 1]]), r"fractures\[0\]: set index 0.0 is not an integer"),
    (good_json(fractures=[[0, 0, "1", 1, 1]]), r"fractures\[0\]: y0 = '1' is not a number"),
    (good_json(fractures=[[0, 0, 0, None, 1]]), r"fractures\[0\]: x1 = None is not a number"),
    (good_json(fractures=[[0, 0, 0, True, 1]]), r"fractures\[0\]: x1 = True is not a number"),
    (good_json(fractures=[[0, 1, 2, 1, 2]]), r"fractures\[0\]: zero-length fracture"),
    (
        JSON_HEAD + '"fractures": [[0, NaN, 0, 1, 1]]}',
        r"fractures\[0\]: x0 = nan is not finite",
    ),
    (
        JSON_HEAD + '"fractures": [[0, 0, 0, 1e999, 1]]}',
        r"fractures\[0\]: x1 = inf is not finite",
    ),
]


@pytest.mark.parametrize(("content", "match"), JSON_ERRORS)
def test_json_errors(tmp_path, content, match):
    path = tmp_path / "bad.json"
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    with pytest.raises(DfnError, match=match) as info:
        load_network(path)
    assert str(path) in str(info.value)


def test_good_json_loads(tmp_path):
    path = tmp_path / "good.json"
    path.write_text(json.dumps(good_json()))
    net = load_network(path)
    assert net.set_names == ("a", "b")
    assert net.segments.tolist() == [[[0, 0], [1, 1]], [[2, 0], [2, 1]]]
