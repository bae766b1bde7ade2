"""A texture that declares a huge size is refused from its header, before any decoding."""

from __future__ import annotations

import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse.readers import textures

ROOT = Path(__file__).resolve().parents[1]


def _png(path: Path, width: int, height: int, rows: int) -> None:
    """An RGB PNG whose header declares width x height but that holds only ``rows`` rows."""

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + b"\x80" * (3 * width) for _ in range(rows))
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )


def test_declared_size_above_the_limit_is_refused(tmp_path):
    # complete pixel data, compressed ~1000:1: a plausible file that decodes to 243 MB
    big = tmp_path / "bomb.png"
    _png(big, 9000, 9000, rows=9000)
    assert big.stat().st_size < 2_000_000
    with pytest.raises(textures.TextureError, match="declares 9000 x 9000"):
        textures.sample(big, (0.5, 0.5))


def test_header_claiming_more_than_the_file_holds_is_refused(tmp_path):
    big = tmp_path / "bomb.png"
    _png(big, 30000, 30000, rows=2)
    with pytest.raises(textures.TextureError):
        textures.sample(big, (0.5, 0.5))


def test_refusal_costs_no_memory(tmp_path):
    big = tmp_path / "bomb.png"
    _png(big, 30000, 30000, rows=2)
    code = (
        "import sys; from openpbr_diffuse.readers import textures\n"
        "open('/proc/self/clear_refs', 'w').write('5')  # peak RSS from here on (imports excluded)\n"
        "try:\n    textures.sample(sys.argv[1], (0.5, 0.5))\nexcept textures.TextureError:\n    pass\n"
        "print(next(int(l.split()[1]) for l in open('/proc/self/status') if l.startswith('VmHWM:')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, str(big)],
        capture_output=True,
        text=True,
        check=True,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
        timeout=120,
    )
    assert int(out.stdout.split()[-1]) < 600_000  # KB: the 2.7 GB decode never happens


def test_small_texture_still_reads(tmp_path):
    small = tmp_path / "small.png"
    _png(small, 4, 4, rows=4)
    assert np.allclose(textures.sample(small, (0.5, 0.5)), 0x80 / 255, atol=1e-3)
