"""The README's example runs and writes its plot (needs matplotlib, an optional dependency)."""

import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ARM

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "arm_bend_inflate.py"


def test_example_plots_the_bent_inflated_arm(tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "arm.png"
    result = subprocess.run([sys.executable, str(EXAMPLE), str(ARM), str(png)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    assert len(EXAMPLE.read_text().splitlines()) <= 20
