import numpy as np
import pytest

import murk
from conftest import LASER_GRID, cli, needs_cli

tal = pytest.importorskip("tal", reason="y-tal is not installed (pip install y-tal)")


def small():
    return murk.synth("z:2.0", kind="laser-grid", wall_size=2, grid=8, bins=256,
                      bin_width=0.01, start=3.5, cosines=True)


def test_h_is_a_read_only_view_without_a_copy():
    cap = small()
    h = cap.H
    assert h.shape == (8, 8, 1, 1, 256) and h.dtype == np.float32
    assert h.flags.c_contiguous and not h.flags.writeable and not h.flags.owndata
    # Two views share one buffer: the capture's own.
    assert np.shares_memory(h, cap.H)
    assert cap.t[0] == 3.5 and cap.t.shape == (256,) and cap.bins == 256
    assert cap.laser_points.shape == (8, 8, 3) and cap.sensor_points.shape == (1, 1, 3)
    with pytest.raises(ValueError):
        h[0, 0, 0, 0, 0] = 1.0


@needs_cli
def test_python_synth_writes_the_cli_bytes(tmp_path):
    cli("synth", "--out", tmp_path / "cli.h5", *LASER_GRID)
    cap = murk.synth("z:2.0", kind="laser-grid", wall_size=2, grid=24, bins=768,
                     bin_width=0.005, start=3.5, cosines=True)
    murk.write_capture(tmp_path / "py.h5", cap)
    assert (tmp_path / "py.h5").read_bytes() == (tmp_path / "cli.h5").read_bytes()
    again = murk.read_capture(tmp_path / "cli.h5")
    assert np.array_equal(again.H, cap.H)


@pytest.mark.parametrize("kind", ["laser-grid", "confocal", "single", "exhaustive"])
def test_y_tal_capture_goes_in_and_out(kind):
    target = "z:2.0" if kind == "laser-grid" else "point:0.1,0,0.8"
    start = 3.5 if kind == "laser-grid" else 0.0
    cap = murk.synth(target, kind=kind, wall_size=2 if kind == "laser-grid" else 1, grid=6,
                     bins=512, bin_width=0.01, start=start, cosines=True)
    data = cap.to_tal()
    assert isinstance(data, tal.io.capture_data.NLOSCaptureData)
    # y-tal keeps time first; murk keeps it last.
    assert np.array_equal(data.H, np.moveaxis(cap.H, -1, 0))
    assert data.delta_t == np.float32(cap.bin_width_m)
    back = murk.Capture.from_tal(data)
    assert np.array_equal(back.H, cap.H)
    assert back.kind == cap.kind and back.pairing == cap.pairing
    assert np.allclose(back.laser_points, cap.laser_points, atol=1e-6)
    assert np.allclose(back.sensor_points, cap.sensor_points, atol=1e-6)
    assert back.bin_width_m == float(np.float32(cap.bin_width_m))
    assert back.start_m == float(np.float32(cap.start_m))


def test_from_tal_errors_name_the_data_not_a_deleted_file():
    data = small().to_tal()
    data.laser_grid_xyz = data.laser_grid_xyz[:-1]     # y-tal writes it as it is
    with pytest.raises(murk.FormatError) as e:
        murk.Capture.from_tal(data)
    # It named the temporary file the data passed through, deleted by then.
    assert str(e.value) == ("the y-tal capture: 'laser_grid_normals' has shape [8, 8, 3] but "
                            "'laser_grid_xyz' has [7, 8, 3]")


def test_a_capture_y_tal_wrote_reads_and_reconstructs(tmp_path):
    cap = small()
    path = tmp_path / "tal.hdf5"
    tal.io.write_capture(str(path), cap.to_tal())
    rec = murk.reconstruct(path, "bp", volume="-0.9:0.9:9,-0.9:0.9:9,1.5:2.5:9")
    assert rec.intensity.shape == (9, 9, 9) and rec.intensity.max() > 0
