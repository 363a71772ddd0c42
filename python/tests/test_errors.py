import math

import numpy as np
import pytest

import murk
from conftest import SCENES

VOL = "-0.9:0.9:5,-0.9:0.9:5,1.5:2.5:5"


@pytest.fixture(scope="module")
def cap():
    return murk.synth("z:2.0", kind="laser-grid", wall_size=2, grid=8, bins=256, bin_width=0.01,
                      start=3.5)


def one_line(e):
    msg = str(e.value)
    assert msg and "\n" not in msg and "panicked" not in msg
    return msg


def test_unknown_method(cap):
    with pytest.raises(murk.InputError) as e:
        murk.reconstruct(cap, "pff", volume=VOL)
    assert isinstance(e.value, ValueError)
    assert one_line(e) == "unknown method 'pff'; expected one of pf, pf-exact, bp, fbp, lct, fk, cdt"


def test_bad_volume_string(cap):
    with pytest.raises(murk.InputError) as e:
        murk.reconstruct(cap, volume="-1:1:5,oops")
    assert "oops" in one_line(e) or "volume" in one_line(e)


def test_missing_file():
    with pytest.raises(murk.FileError) as e:
        murk.read_capture("/nonexistent/capture.h5")
    assert isinstance(e.value, OSError)
    assert one_line(e).startswith("/nonexistent/capture.h5: ")
    with pytest.raises(murk.FileError):
        murk.reconstruct("/nonexistent/capture.h5")


def test_not_a_capture(tmp_path):
    p = tmp_path / "x.h5"
    p.write_bytes(b"not hdf5 at all")
    with pytest.raises(murk.FormatError) as e:
        murk.read_capture(p)
    assert one_line(e).startswith(str(p))


@pytest.mark.parametrize("kw", [dict(wavelength=math.nan), dict(wavelength=-1.0),
                                dict(cycles=0.0), dict(gate="soon"), dict(t_offset="later"),
                                dict(window_end="never"), dict(compensate="paper")])
def test_bad_parameters(cap, kw):
    with pytest.raises(murk.InputError) as e:
        murk.reconstruct(cap, volume=VOL, **kw)
    one_line(e)


@pytest.mark.parametrize("kw, needle", [
    (dict(albedo=0.5), "they would be ignored"),
    (dict(mu_t=1.0), "they would be ignored"),
    (dict(compensate="none", mu_t=1.0), "they would be ignored"),
    (dict(compensate="ballistic", mu_t=1.0, albedo=0.5), "'ballistic' does not read an albedo"),
    (dict(slab_thickness=0.02), "slab parameters are read only by cdt"),
])
def test_knobs_that_would_be_ignored_are_refused(cap, kw, needle):
    with pytest.raises(murk.InputError) as e:
        murk.reconstruct(cap, volume=VOL, **kw)
    assert needle in one_line(e)


@pytest.mark.parametrize("level", [-1, 10, 2**40])
def test_a_compression_level_out_of_range_is_named(cap, tmp_path, level):
    with pytest.raises(murk.InputError) as e:
        murk.write_capture(tmp_path / "c.h5", cap, compression=level)
    assert one_line(e) == f"compression must be 0 (none) to 9, got {level}"


def test_confocal_methods_refuse_a_laser_grid(cap):
    with pytest.raises(murk.Error) as e:
        murk.reconstruct(cap, "fk")
    one_line(e)


def test_bad_render_arguments(tmp_path):
    with pytest.raises(murk.FileError):
        murk.render(tmp_path / "none.toml")
    with pytest.raises(murk.FormatError) as e:
        murk.render("[capture]\nkind = 3\n")
    one_line(e)
    with pytest.raises(murk.InputError) as e:
        murk.synth("z:2.0", kind="bogus")
    assert one_line(e).startswith("unknown capture kind 'bogus'")
    with pytest.raises(murk.InputError):
        murk.merge([])


@pytest.mark.parametrize("albedos, msg", [
    ([], "an albedo sweep takes 1 to 16 albedos, got 0"),
    ([0.5, 0.5], "albedo 0.5 appears twice in the sweep"),
])
def test_bad_albedo_sweeps_are_refused_by_the_renderer(albedos, msg):
    scene = SCENES / "z-letter.toml"
    with pytest.raises(murk.InputError) as e:
        murk.render_albedos(scene, albedos, grid=4, spp=4)
    assert one_line(e) == msg


def test_absurd_render_magnitudes(tmp_path):
    scene = SCENES / "z-letter.toml"
    with pytest.raises(murk.LimitError) as e:
        murk.render(scene, grid=4, spp=1, threads=100000)
    assert "at most 1024" in one_line(e)
    for every in (math.inf, math.nan, -1.0, 1e300):
        with pytest.raises(murk.InputError) as e:
            murk.render(scene, grid=4, spp=1, checkpoint=tmp_path / "c.ckpt", checkpoint_every=every)
        assert "one year" in one_line(e)
    with pytest.raises(murk.InputError) as e:
        murk.render(scene, grid=4, spp=2**41)
    assert "spp must be between 1 and" in one_line(e)


def test_render_outputs_checked_before_rendering(tmp_path):
    scene = tmp_path / "z.toml"
    scene.write_text((SCENES / "z-letter.toml").read_text())
    before = scene.read_bytes()
    with pytest.raises(murk.InputError) as e:
        murk.render(scene, grid=4, spp=1, out=scene)
    assert "replace the input" in one_line(e)
    assert scene.read_bytes() == before
    with pytest.raises(murk.InputError) as e:
        murk.render(scene, grid=4, spp=1, out=tmp_path / "no" / "such" / "c.h5")
    assert "does not exist" in one_line(e)


def test_argument_conversion_errors_name_the_keyword(tmp_path):
    with pytest.raises(murk.InputError) as e:
        murk.synth("z:1", grid=-1)
    assert one_line(e).startswith("grid: ")
    with pytest.raises(murk.InputError) as e:
        murk.render(SCENES / "z-letter.toml", grid=4, spp=2.0)
    assert one_line(e).startswith("spp: ")
    with pytest.raises(murk.InputError) as e:
        murk.render(SCENES / "z-letter.toml", grid=4, spp=1, threads=-1)
    assert "threads must be ≥ 0" in one_line(e)


def test_checkpoint_and_output_must_differ(tmp_path):
    out = tmp_path / "z.h5"
    with pytest.raises(murk.InputError) as e:
        murk.render(SCENES / "z-letter.toml", grid=4, spp=1, checkpoint=out, out=out)
    assert "the checkpoint and the output are the same file" in one_line(e)
    assert not out.exists()


def test_numpy_values_as_overrides():
    a = murk.render(SCENES / "z-letter.toml", grid=4, spp=1, set={
        "object[0].center": np.array([0.0, 0.0, 1.5]), "medium.albedo": np.float64(0.5)})
    b = murk.render(SCENES / "z-letter.toml", grid=4, spp=1, set={
        "object[0].center": [0.0, 0.0, 1.5], "medium.albedo": 0.5})
    assert np.array_equal(a.H, b.H)


def test_unknown_compensation_is_named(cap):
    with pytest.raises(murk.InputError) as e:
        murk.reconstruct(cap, volume=VOL, compensate="foo")
    assert "foo" in one_line(e) and "ballistic" in one_line(e)


def test_damaged_pickle_state(cap):
    rebuild, (state,) = cap.__reduce__()
    for key, value, says in [("h", b"abc", "H is not whole f32 values"),
                             ("time", (3.5, 0.01, 3), "expected 64 histograms × 3 bins"),
                             ("time", (3.5, -0.01, 256), "bin width must be a positive")]:
        with pytest.raises(murk.InputError) as e:
            rebuild({**state, key: value})
        assert one_line(e).startswith("pickled capture: ") and says in one_line(e)


def test_huge_thread_counts_are_input_errors(cap):
    for call in (lambda: murk.reconstruct(cap, volume=VOL, threads=2**70),
                 lambda: murk.render(SCENES / "z-letter.toml", grid=4, spp=1, threads=2**70)):
        with pytest.raises(murk.InputError) as e:
            call()
        assert one_line(e).startswith("threads: ")
