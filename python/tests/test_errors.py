import math
import os
import subprocess

import numpy as np
import pytest

import murk
from conftest import MURK, SCENES, needs_cli

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
    # The list comes from the library's one method table, in its order.
    names = ", ".join(murk.methods())
    assert one_line(e) == f"unknown method 'pff'; expected one of {names}"
    assert names.startswith("pf, pf-exact, ") and "dlct" in names


def test_bad_volume_string(cap):
    with pytest.raises(murk.InputError) as e:
        murk.reconstruct(cap, volume="-1:1:5,oops")
    assert "oops" in one_line(e) or "volume" in one_line(e)


def test_reversed_volume_bounds_are_refused_naming_the_volume_not_a_flag(cap):
    with pytest.raises(murk.InputError) as e:
        murk.reconstruct(cap, volume="1:0:10,-0.9:0.9:5,1.5:2.5:5")
    msg = one_line(e)
    assert "runs from 1 down to 0" in msg and "--volume" not in msg, msg


def test_dir_lists_the_api_not_the_imports():
    names = set(dir(murk))
    assert not names & {"Any", "Dict", "np", "os", "re", "functools", "types"}, names
    assert {"reconstruct", "render", "Capture", "InputError", "experiment", "dask"} <= names


def test_capture_repr_has_no_float_noise(tmp_path, cap):
    # Files hold the time axis as f32: 0.0048 reads back as 0.004800000227987766.
    c = murk.synth("z:2.0", kind="laser-grid", wall_size=2, grid=8, bins=256, bin_width=0.0048,
                   start=3.5)
    murk.write_capture(tmp_path / "c.h5", c)
    r = repr(murk.read_capture(tmp_path / "c.h5"))
    assert "by 0.0048 m" in r and "t from 3.5 m" in r, r


def test_reconstruction_repr_is_one_line(cap):
    # Not the dataclass's repr: the whole intensity array and the axes' float noise.
    r = repr(murk.reconstruct(cap, volume=VOL))
    assert r == ("<murk.Reconstruction Phasor Fields (fast form): 5 × 5 × 5 voxels, x -0.9..0.9 m, "
                 "y -0.9..0.9 m, z 1.5..2.5 m>"), r


def test_a_bad_override_is_an_input_error_not_a_format_error():
    # The scene file is fine; the caller's `set` is not.
    with pytest.raises(murk.InputError) as e:
        murk.render(os.path.join(SCENES, "z-letter.toml"), grid=4, spp=1, set={"medium.foo": 1})
    assert not isinstance(e.value, murk.FormatError)
    assert "medium.foo=1" in one_line(e) and "unknown field `foo`" in one_line(e)
    # Errors quote the keywords as Python spells them, never the command line's flags.
    assert 'set item "medium.foo=1"' in one_line(e) and "--set" not in one_line(e)
    with pytest.raises(murk.InputError) as e:
        murk.render(os.path.join(SCENES, "z-letter.toml"), grid=0, spp=1)
    assert "--grid" not in one_line(e)
    with pytest.raises(murk.InputError) as e:
        murk.render(os.path.join(SCENES, "z-letter.toml"), bins=1 << 40, spp=1)
    assert "(from bins=1099511627776)" in one_line(e) and "--bins" not in one_line(e)
    with pytest.raises(murk.InputError) as e:
        murk.render(os.path.join(SCENES, "z-letter.toml"), grid=4, spp=1, set=["medium.albedo"])
    assert one_line(e).endswith('set item "medium.albedo": expected KEY=VALUE, e.g. medium.albedo=0.83')


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


def test_keywords_of_the_wrong_kind_are_named(cap, tmp_path):
    scene = SCENES / "z-letter.toml"
    for call, want in [
        (lambda: murk.render(scene, grid=4, spp=1, progress=5),
         "progress: expected True, False, None or a callable (done, total), got 5"),
        # None was a plain render, returned as a list of one.
        (lambda: murk.render_albedos(scene, None, grid=4, spp=1),
         "albedos: expected a list of numbers, got None"),
        (lambda: murk.render_albedos(scene, [0.5, "x"], grid=4, spp=1),
         "albedos: expected a list of numbers, got [0.5, 'x']"),
        # Before, the scene file was blamed for the keyword's value.
        (lambda: murk.render(scene, grid=0, spp=1), "grid must be a whole number ≥ 1, got 0"),
        (lambda: murk.render(scene, bins=True, spp=1), "bins must be a whole number ≥ 1, got True"),
        (lambda: murk.reconstruct(None), "capture: expected a path, got NoneType"),
        (lambda: murk.merge([cap, 3]), "parts: expected a path, got int"),
        # An empty path named the current folder: the study planned into it.
        (lambda: murk.render(scene, grid=4, spp=1, out=""), "out: the path is empty"),
        (lambda: murk.experiment.plan(""), "out: the path is empty"),
        (lambda: murk.render(scene, grid=4, spp=1, threads="2"), "threads: "),
        (lambda: murk.read_capture(""), "path: the path is empty"),
        (lambda: murk.render_albedos(scene, b"0.3", grid=4, spp=1),
         "albedos: expected a list of numbers, got b'0.3'"),
    ]:
        with pytest.raises(murk.InputError) as e:
            call()
        assert one_line(e).startswith(want), one_line(e)


def test_paths_as_bytes_and_sweeps_as_text_are_taken(tmp_path):
    scene = SCENES / "z-letter.toml"
    a = murk.render(os.fsencode(scene), grid=2, spp=2)
    b = murk.render(scene, grid=2, spp=2)
    assert np.array_equal(a.H, b.H)
    swept = murk.render_albedos(scene, "0.3,0.6", grid=2, spp=2)
    listed = murk.render_albedos(scene, [0.3, 0.6], grid=2, spp=2)
    assert all(np.array_equal(x.H, y.H) for x, y in zip(swept, listed))
    murk.write_capture(os.fsencode(tmp_path / "b.h5"), b)
    assert np.array_equal(murk.read_capture(os.fsencode(tmp_path / "b.h5")).H, b.H)
    rec = murk.reconstruct(os.fsencode(tmp_path / "b.h5"), "bp", volume=VOL, progress=np.False_)
    assert rec.intensity.shape == (5, 5, 5)


def test_an_extinction_beyond_radiative_transfer_is_refused(cap):
    past = "a mean free path below the 1 µm where radiative transfer holds"
    with pytest.raises(murk.InputError) as e:
        murk.reconstruct(cap, volume=VOL, compensate="ballistic", mu_t=1e300)
    assert one_line(e).startswith("μt is 1e300 /m, " + past)
    with pytest.raises(murk.InputError) as e:
        murk.render(SCENES / "z-letter.toml", grid=2, spp=1, set={"medium.mu_t": 2e6})
    assert 'medium.mu_t (from set item "medium.mu_t=2000000.0"): is 2e6 /m, ' + past in one_line(e)
    with pytest.raises(murk.InputError) as e:
        murk.synth("z:2.0", mu_t=1e7)
    assert past in one_line(e)


def test_a_mesh_the_scene_reads_is_never_replaced(tmp_path):
    mesh = tmp_path / "mesh.h5"
    mesh.write_text("v 0 0 1\nv 0.3 0 1\nv 0 0.3 1\nf 1 2 3\n")
    scene = tmp_path / "mesh.toml"
    scene.write_text((SCENES / "z-letter.toml").read_text().replace(
        'shape = "z-letter"\ncenter = [0.0, 0.0, 2.0]', 'shape = "mesh"\nfile = "mesh.h5"'))
    with pytest.raises(murk.InputError) as e:
        murk.render(scene, grid=2, spp=1, out=mesh)
    assert "the output would replace the input" in one_line(e) and "mesh.h5" in one_line(e)
    # The checkpoint is replaced as the render goes, and removed once it is done.
    with pytest.raises(murk.InputError) as e:
        murk.render(scene, grid=2, spp=1, checkpoint=mesh)
    assert "the checkpoint would replace the input" in one_line(e)
    assert mesh.read_text().startswith("v 0 0 1")


def test_warnings_and_errors_name_keywords_not_flags(tmp_path):
    # A window cut in the middle of the Z's echo, kept as it is: the library warns and suggests
    # the option that handles it, spelled as Python takes it (the CLI spells it as its flag).
    short = murk.synth("z:2.0", kind="laser-grid", wall_size=2, grid=8, bins=60, bin_width=0.01,
                       start=3.5)
    rec = murk.reconstruct(short, volume=VOL, window_end="keep")
    strong = [w for w in rec.warnings if "ends while the signal is strong" in w]
    assert strong and "window_end='keep'" in strong[0] and "--" not in strong[0], rec.warnings
    # An import error names the keywords to give.
    p = tmp_path / "scan.npy"
    np.save(p, np.zeros((16, 4, 4), dtype=np.float32))
    with pytest.raises(murk.InputError) as e:
        murk.import_capture(p, axes="t,x,y", confocal=True)
    msg = one_line(e)
    assert "(wall_size)" in msg and "bin_width_ps or bin_width_m" in msg and "--" not in msg, msg
    with pytest.raises(murk.UnsupportedError) as e:
        murk.import_capture(p, axes="t,x,y")
    msg = one_line(e)
    assert "give confocal=True" in msg and "format preset" in msg and "--" not in msg, msg


@needs_cli
def test_the_cli_names_its_flags_for_the_same_warning(tmp_path):
    short = murk.synth("z:2.0", kind="laser-grid", wall_size=2, grid=8, bins=60, bin_width=0.01,
                       start=3.5)
    murk.write_capture(tmp_path / "short.h5", short)
    r = subprocess.run([str(MURK), "reconstruct", str(tmp_path / "short.h5"), "--out",
                        str(tmp_path / "v.npy"), "--volume", VOL, "--window-end", "keep"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "drop --window-end keep" in r.stderr and "window_end=" not in r.stderr, r.stderr
