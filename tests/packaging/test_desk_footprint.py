"""The desk stays light: its modules do not pull in the numba compiler.

numba (with LLVM) adds about 110 MB to a process and compiles on the first start after an
install; the robot's planners use it, the desk's window, headless run and meter reader
do not need it.
"""

import os
import subprocess
import sys


def test_the_desk_and_the_meter_reader_load_without_numba():
    code = ("import sys\n"
            "import app.cli, app.headless, app.ui.app, app.core.desk, app.core.meter.reader\n"
            "import app.core.meter.calibrated\n"
            "print('numba' in sys.modules, 'llvmlite' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=300, env={**os.environ, "QT_QPA_PLATFORM": "offscreen"})
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False", "False"], out.stdout
