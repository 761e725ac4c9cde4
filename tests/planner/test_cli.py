"""`python -m app.core.planner plan`: JSON out, clear messages for bad input."""

import json
import subprocess
import sys

import pytest

MAP = """type octile
height 5
width 7
map
.......
.@@@@@.
.....@.
.@@@.@.
.......
"""


def run(*args):
    return subprocess.run([sys.executable, "-m", "app.core.planner", "plan", *args],
                          capture_output=True, text=True, timeout=120)


@pytest.fixture
def small_map(tmp_path):
    p = tmp_path / "small.map"
    p.write_text(MAP)
    return p


@pytest.mark.parametrize("algo", ["astar", "jps"])
def test_plans_and_prints_json(small_map, algo):
    r = run("--map", str(small_map), "2,0", "2,4", "--algo", algo, "--cells")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["found"] and out["cells"][0] == [2, 0] and out["cells"][-1] == [2, 4]
    assert out["length_cells"] == pytest.approx(4.0)


def test_unreachable_goal_is_not_an_error(tmp_path):
    p = tmp_path / "walled.map"
    p.write_text("type octile\nheight 3\nwidth 3\nmap\n.@.\n.@.\n.@.\n")
    r = run("--map", str(p), "0,0", "0,2")
    assert r.returncode == 0
    assert json.loads(r.stdout)["found"] is False


def test_bad_inputs_exit_2_with_one_line(small_map, tmp_path):
    for args, words in ((["--map", str(tmp_path / "none.map"), "0,0", "1,1"], "not found"),
                        (["--map", str(small_map), "1,1", "0,0"], "blocked"),
                        (["--map", str(small_map), "0,0", "99,99"], "outside")):
        r = run(*args)
        assert r.returncode == 2
        assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1
