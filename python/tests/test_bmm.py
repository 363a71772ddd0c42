"""The boundary migration model from Python: murk.import_capture(path, "bmm") and
murk.reconstruct(cap, "bmm", medium_n=..., medium_musp=..., medium_mua=...) give what
`murk import --format bmm` and `murk reconstruct --method bmm --medium-*` write, byte for byte."""

import struct
from pathlib import Path

import numpy as np
import pytest

import murk
from conftest import cli

REAL = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "real" / "bmm_du2022"


def write_mat_v5(path, name, array):
    """A MATLAB v5 file holding one uncompressed double array (column-major, as MATLAB stores it)."""
    def element(kind, payload):
        pad = (-len(payload)) % 8
        return struct.pack("<II", kind, len(payload)) + payload + b"\0" * pad

    flags = element(6, struct.pack("<II", 6, 0))  # miUINT32: mxDOUBLE_CLASS
    dims = element(5, struct.pack(f"<{array.ndim}i", *array.shape))  # miINT32
    label = element(1, name.encode())  # miINT8
    data = element(9, np.asarray(array, "<f8").tobytes(order="F"))  # miDOUBLE
    body = flags + dims + label + data
    header = b"MATLAB 5.0 MAT-file, murk test".ljust(116) + b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"
    Path(path).write_bytes(header + struct.pack("<II", 14, len(body)) + body)


@pytest.fixture(scope="module")
def foam(tmp_path_factory):
    """A 16 × 16 × 256 scan of a diffusive medium's surface (55 ps bins): every point's return rises
    at bin 20 and decays over ~30 bins, and a bright patch left of centre returns later and longer,
    as an object inside the medium does. Named as the 4 cm capture, which gives its scan side."""
    n, nt = 16, 256
    t = np.arange(nt)
    surface = np.where(t >= 20, (t - 19.0) * np.exp(-(t - 20) / 10.0), 0.0)
    deep = np.where(t >= 30, (t - 29.0) ** 2 * np.exp(-(t - 30) / 15.0), 0.0)
    raw = np.empty((n, n, nt))
    for a in range(n):
        for b in range(n):
            raw[a, b] = 50 * surface + (5 * deep if 5 <= a < 9 and 3 <= b < 8 else 0.0) + 1.0
    path = tmp_path_factory.mktemp("bmm") / "4cmFoam_LambertianT_7cmFoam.mat"
    write_mat_v5(path, "raw_data", raw)
    return path


def test_import_is_the_clis(foam, tmp_path):
    cli("import", foam, "--format", "bmm", "--out", tmp_path / "cli.h5", "--quiet")
    want = murk.read_capture(tmp_path / "cli.h5")
    cap = murk.import_capture(foam, "bmm")
    assert cap.H.tobytes() == want.H.tobytes()
    assert cap.scene_info == want.scene_info and "medium_n: 1.23" in cap.scene_info
    # The file stores the points in single precision; written, they are the CLI's.
    murk.write_capture(tmp_path / "py.h5", cap)
    assert (tmp_path / "py.h5").read_bytes() == (tmp_path / "cli.h5").read_bytes()
    # A given scan side replaces the one the file name gives.
    wide = murk.import_capture(foam, "bmm", wall_size=0.4)
    span = np.ptp(wide.sensor_points.reshape(-1, 3)[:, 0])
    assert span == pytest.approx(0.4)


@pytest.mark.parametrize("flags,kw", [
    ([], {}),
    (["--medium-n", "1.3", "--medium-musp", "250", "--medium-mua", "0.5"],
     dict(medium_n=1.3, medium_musp=250.0, medium_mua=0.5)),
])
def test_reconstruct_bmm_is_the_clis(foam, tmp_path, flags, kw):
    cap_path = tmp_path / "foam.h5"
    cli("import", foam, "--format", "bmm", "--out", cap_path, "--quiet")
    cli("reconstruct", cap_path, "--method", "bmm", *flags, "--out", tmp_path / "v.npy", "--quiet")
    want = np.load(tmp_path / "v.npy")
    for src in (cap_path, murk.read_capture(cap_path)):
        rec = murk.reconstruct(src, "bmm", **kw)
        assert rec.intensity.shape == want.shape
        assert rec.intensity.tobytes() == want.tobytes()
    assert rec.params["medium"].startswith(f"n {kw.get('medium_n', 1.23)}"), rec.params


def test_medium_keywords_are_read(foam):
    cap = murk.import_capture(foam, "bmm")
    base = murk.reconstruct(cap, "bmm")
    for kw in (dict(medium_n=1.4), dict(medium_musp=200.0), dict(medium_mua=20.0)):
        other = murk.reconstruct(cap, "bmm", **kw)
        assert other.intensity.tobytes() != base.intensity.tobytes(), kw
    # The capture's own constants are the defaults: giving them changes nothing.
    same = murk.reconstruct(cap, "bmm", medium_n=1.23, medium_musp=313.0, medium_mua=0.0)
    assert same.intensity.tobytes() == base.intensity.tobytes()


def test_bad_bmm_input_is_one_line(foam, tmp_path):
    with pytest.raises(murk.InputError, match="medium constants does not apply to pf"):
        murk.reconstruct(murk.import_capture(foam, "bmm"), "pf", medium_n=1.3)
    with pytest.raises(murk.InputError, match="format 'bmmm': expected .*bmm"):
        murk.import_capture(foam, "bmmm")
    other = tmp_path / "raw.mat"
    write_mat_v5(other, "counts", np.ones((4, 4, 8)))
    with pytest.raises(murk.Error) as e:
        murk.import_capture(other, "bmm", wall_size=0.2)
    assert "no variable 'raw_data'" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(murk.InputError, match="not an axis"):
        murk.import_capture(foam, axes="t,x,q", confocal=True)


@pytest.mark.skipif(not REAL.exists(), reason=f"needs the real foam captures in {REAL}")
def test_real_foam_capture_reads_as_the_cli(tmp_path):
    mat = REAL / "4cmFoam_LambertianT_7cmFoam.mat"
    cli("import", mat, "--format", "bmm", "--out", tmp_path / "t4.h5", "--quiet")
    cli("reconstruct", tmp_path / "t4.h5", "--method", "bmm", "--out", tmp_path / "v.npy",
        "--quiet")
    murk.write_capture(tmp_path / "py.h5", murk.import_capture(mat, "bmm"))
    assert (tmp_path / "py.h5").read_bytes() == (tmp_path / "t4.h5").read_bytes()
    rec = murk.reconstruct(tmp_path / "py.h5", "bmm")
    assert rec.intensity.tobytes() == np.load(tmp_path / "v.npy").tobytes()
