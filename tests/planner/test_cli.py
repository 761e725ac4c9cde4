"""`python -m app.core.planner plan`: JSON out, clear messages for bad input.

One test runs the command as a process; the others call its ``main`` in this process
(the same argument list, exit code, stdout and stderr), a process start with its
imports and kernel loads costing a second or more each, several on a loaded machine."""

import json
import subprocess
import sys

import pytest

from app.core.planner.__main__ import main

pytestmark = pytest.mark.slow(24)

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
    """``python -m app.core.planner plan ARGS`` as a process."""
    return subprocess.run([sys.executable, "-m", "app.core.planner", "plan", *args],
                          capture_output=True, text=True, timeout=120)


@pytest.fixture
def plan(capsys):
    """The same command's ``main`` called here: what :func:`run` returns, without a
    process of its own."""
    def call(*args):
        code = main(["plan", *map(str, args)])
        out = capsys.readouterr()
        return subprocess.CompletedProcess(["plan", *args], code, out.out, out.err)
    return call


@pytest.fixture
def small_map(tmp_path):
    p = tmp_path / "small.map"
    p.write_text(MAP)
    return p


def _planned_around_the_wall(r):
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["found"] and out["cells"][0] == [2, 0] and out["cells"][-1] == [2, 4]
    assert out["length_cells"] == pytest.approx(4.0)


def test_the_command_as_a_process_exits_with_mains_code_and_its_one_line(small_map):
    r = run("--map", str(small_map), "1,1", "0,0")  # a start on the wall
    assert r.returncode == 2
    assert r.stderr.strip() == "planner: start cell row 1, col 1 is blocked (on an obstacle)"


@pytest.mark.parametrize("algo", ["astar", "jps"])
def test_plans_and_prints_json(plan, small_map, algo):
    _planned_around_the_wall(plan("--map", str(small_map), "2,0", "2,4", "--algo", algo,
                                  "--cells"))


def test_unreachable_goal_is_not_an_error(plan, tmp_path):
    p = tmp_path / "walled.map"
    p.write_text("type octile\nheight 3\nwidth 3\nmap\n.@.\n.@.\n.@.\n")
    r = plan("--map", str(p), "0,0", "0,2")
    assert r.returncode == 0
    assert json.loads(r.stdout)["found"] is False


def test_bad_inputs_exit_2_with_one_line(plan, small_map, tmp_path):
    for args, words in ((["--map", str(tmp_path / "none.map"), "0,0", "1,1"], "not found"),
                        (["--map", str(small_map), "1,1", "0,0"], "blocked"),
                        (["--map", str(small_map), "0,0", "99,99"], "outside")):
        r = plan(*args)
        assert r.returncode == 2
        assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_errors_speak_the_units_they_were_given(plan, tmp_path):
    """With --metres a bad point is named in metres with the map's extent in
    metres, never as a cell the user did not type (issue 12, C)."""
    (tmp_path / "m.pgm").write_bytes(b"P5\n10 8\n255\n" + bytes([254] * 80))
    (tmp_path / "m.yaml").write_text("image: m.pgm\nresolution: 0.5\norigin: [1.0, 2.0, 0.0]\n"
                                     "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    r = plan("--map", str(tmp_path / "m.yaml"), "--metres", "40,3", "2,3")
    assert r.returncode == 2
    assert "start x 40 m, y 3 m lies outside the map (the map spans x 1..6 m, y 2..6 m)" \
        in r.stderr
    assert "(" + "3, 78" not in r.stderr and "row" not in r.stderr
    r = plan("--map", str(tmp_path / "m.yaml"), "0,0", "20,3")
    assert r.returncode == 2 and "goal cell row 20, col 3 lies outside the map" in r.stderr
    assert "8 rows and 10 columns" in r.stderr
