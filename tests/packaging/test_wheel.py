"""Build the wheel, install it into a fresh virtual environment outside the source tree,
and run the desk and the meter reader from there, from another working directory.

Choices, so that this runs in a CI minute or so:

* The wheel is built from a copy of the package sources with ``pip wheel --no-deps
  --no-build-isolation`` (setuptools, the build backend, is in the dev extra).
* The fresh venv (``--without-pip``, deleted and made again on every run) gets the
  project venv's dependencies through a ``.pth`` line naming its site-packages — not
  its ``.pth`` files, so the project's editable install stays out. The wheel is
  installed with ``pip --python VENV install --no-index --no-deps --ignore-installed``,
  and the test then checks that every runtime requirement of the installed metadata is
  found. Nothing is downloaded.
* The venv lives at a fixed place in the temp folder (one per checkout), and numba's
  cache (``NUMBA_CACHE_DIR``) beside it is kept between runs, with the installed
  sources' times set from the wheel. numba keys its cache on the source file's folder
  and its content (a SHA-256 of the file), so the kernels the suite compiled before its
  first test (tests/conftest.py, beside the checkout's sources) are copied to the
  installed files' places in that cache: the installed desk and robot load them rather
  than compiling them again (≈ 40 s of CPU). Whatever is not there is compiled, as on a
  user's first run; the headless demo's own test covers a start from an empty cache.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
pytestmark = [pytest.mark.e2e, pytest.mark.timeout(600), pytest.mark.slow(20)]


def _home() -> Path:
    tag = hashlib.sha1(str(ROOT).encode()).hexdigest()[:10]
    return Path(tempfile.gettempdir()) / f"station-patrol-wheel-{tag}"


def _run(args, *, cwd, env, timeout=300) -> subprocess.CompletedProcess:
    out = subprocess.run([str(a) for a in args], cwd=cwd, env=env, capture_output=True,
                         text=True, timeout=timeout)
    assert out.returncode == 0, (f"{' '.join(map(str, args))} exited {out.returncode}:\n"
                                 f"{out.stdout[-3000:]}\n{out.stderr[-3000:]}")
    return out


def _build_wheel(home: Path) -> Path:
    src, dist = home / "src", home / "dist"
    for d in (src, dist):
        shutil.rmtree(d, ignore_errors=True)
    junk = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")
    for pkg in ("app", "sim_robot"):
        shutil.copytree(ROOT / pkg, src / pkg, ignore=junk)
    for f in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / f, src / f)
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
          "--quiet", "-w", dist, src], cwd=home, env=dict(os.environ))
    (wheel,) = dist.glob("station_patrol-*.whl")
    return wheel


def _fresh_venv(home: Path, wheel: Path) -> Path:
    venv = home / "venv"
    shutil.rmtree(venv, ignore_errors=True)
    _run([sys.executable, "-m", "venv", "--without-pip", venv], cwd=home,
         env=dict(os.environ))
    py = venv / ("Scripts/python.exe" if os.name == "nt" else "bin/python")
    site = Path(_run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                     cwd=home, env=dict(os.environ)).stdout.strip())
    deps = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (site / "project-dependencies.pth").write_text("\n".join(sorted(deps)) + "\n")
    _run([sys.executable, "-m", "pip", "--python", py, "install", "--quiet", "--no-index",
          "--no-deps", "--ignore-installed", wheel], cwd=home, env=dict(os.environ))
    # the wheel's times on the installed sources, so numba's cache of an unchanged
    # source stays valid from one run to the next
    with zipfile.ZipFile(wheel) as z:
        for info in z.infolist():
            target = site / info.filename
            if info.filename.endswith(".py") and target.is_file():
                t = time.mktime((*info.date_time, 0, 0, -1))
                os.utime(target, (t, t))
    return py


def _seed_numba_cache(site: Path, cache: Path) -> int:
    """Copy the checkout's compiled kernels (``__pycache__/*.nbi``, ``*.nbc``) to where
    numba looks for those of the installed copy of each source file; how many files."""
    from numba.core.caching import _CacheLocator

    n = 0
    for pkg in ("app", "sim_robot"):
        for f in (ROOT / pkg).rglob("__pycache__/*.nb[ic]"):
            installed = site / f.parent.parent.relative_to(ROOT) / "x.py"
            if not installed.parent.is_dir():
                continue
            target = cache / _CacheLocator.get_suitable_cache_subpath(str(installed))
            target.mkdir(parents=True, exist_ok=True)
            if not (target / f.name).exists():
                shutil.copy2(f, target / f.name)
                n += 1
    return n


def test_wheel_installs_and_runs_outside_the_tree():
    home = _home()
    home.mkdir(parents=True, exist_ok=True)
    wheel = _build_wheel(home)
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
    for shipped in ("app/resources/alarms.toml", "app/resources/station/station.json",
                    "app/resources/station/station_map.png",
                    "app/resources/routes/default.json",
                    "app/resources/gauges/pressure_0_1p6mpa.json",
                    "app/core/meter/models/dial_keypoints.onnx"):
        assert shipped in names, f"{shipped} is not in the wheel"
    py = _fresh_venv(home, wheel)
    bindir = py.parent

    work = Path(tempfile.mkdtemp(prefix="run-", dir=home))  # not the source tree
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    site = Path(_run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                     cwd=home, env=dict(os.environ)).stdout.strip())
    _seed_numba_cache(site, home / "numba-cache")
    env.update(QT_QPA_PLATFORM="offscreen", NUMBA_CACHE_DIR=str(home / "numba-cache"),
               STATION_PATROL_DATA_DIR=str(work / "data"),
               STATION_PATROL_LOG_DIR=str(work / "log"),
               STATION_PATROL_KEY_FILE=str(work / "station.key"))
    try:
        where = json.loads(_run([py, "-c", (
            "import json, importlib.metadata as m, re, app, sim_robot\n"
            "from app.core.paths import resource\n"
            "reqs = [r for r in m.requires('station-patrol') if 'extra ==' not in r]\n"
            "missing = []\n"
            "for r in reqs:\n"
            "    name = re.match(r'[A-Za-z0-9_.-]+', r).group(0)\n"
            "    try:\n"
            "        m.version(name)\n"
            "    except m.PackageNotFoundError:\n"
            "        missing.append(r)\n"
            "print(json.dumps({'app': app.__file__, 'sim': sim_robot.__file__,\n"
            "    'profile': str(resource('gauges', 'pressure_0_1p6mpa.json')),\n"
            "    'missing': missing}))")], cwd=work, env=env).stdout)
        venv = py.parent.parent.resolve()
        for k in ("app", "sim", "profile"):
            assert Path(where[k]).resolve().is_relative_to(venv), (k, where[k])
        assert not where["missing"], f"runtime requirements not found: {where['missing']}"

        exe = bindir / ("station-patrol.exe" if os.name == "nt" else "station-patrol")
        # 3 s of the desk once the robot listens, as the other short headless runs
        # (tests/e2e/test_headless_demo.py): telemetry comes at about 10 a second
        _run([exe, "--demo", "--headless", "--duration", "3", "--out", work / "out"],
             cwd=work, env=env, timeout=400)
        summary = json.loads((work / "out" / "summary.json").read_text())
        assert summary["counts"].get("telemetry", 0) > 0, summary["counts"]
        assert summary["archive"]["path"].startswith(str(work / "data"))

        # the meter reader on a packaged profile, on a dial the installed simulator draws
        image = work / "dial.png"
        _run([py, "-c", "import cv2, sys\n"
              "from sim_robot.gauge_render import render_dial, stock_spec\n"
              "cv2.imwrite(sys.argv[1], render_dial(stock_spec('pressure_0_1p6mpa'), 0.8))",
              image], cwd=work, env=env)
        out = _run([py, "-m", "app.core.meter", "read", "--profile", where["profile"], image],
                   cwd=work, env=env)
        reading = json.loads(out.stdout.splitlines()[0])
        assert reading["error"] is None, reading
        assert reading["unit"] == "MPa"
        assert reading["value"] == pytest.approx(0.8, abs=0.05)
    finally:
        shutil.rmtree(work, ignore_errors=True)
