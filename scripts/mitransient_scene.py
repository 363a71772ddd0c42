"""The mitransient scene pieces that scripts/fog-walk-reference.py and scripts/mitransient-hetero.py share:
Mitsuba set up with mitransient's volumetric integrator, the laser spot, the sensor, the fog's box and the
render. Needs the mitransient venv (mitransient 1.3.1, mitsuba 3.9.1); importing this module alone does not.

mitransient's volumetric integrator has no laser sampling, so the laser spot is a small square area light
0.5 mm in front of the wall (z = 0), and the sensor leg is dropped with camera_unwarp.
"""

import os

import numpy as np

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
INTEGRATOR = "unwarped_prbvolpath"


def mitsuba():
    """Mitsuba in `llvm_ad_mono`, with mitransient's transient_prbvolpath registered as INTEGRATOR."""
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)
    import mitsuba as mi

    mi.set_variant("llvm_ad_mono")
    from mitransient.integrators.transient_prbvolpath import TransientPRBVolpathIntegrator

    class Unwarped(TransientPRBVolpathIntegrator):
        # mitransient refuses camera_unwarp with an nlos_capture_meter; the unwarp itself is generic.
        def check_transient_(self, scene, sensor):
            pass

    mi.register_integrator(INTEGRATOR, lambda props: Unwarped(props))
    return mi


def sensor(origin, res, bins, bin_m, spp):
    """An nlos_capture_meter at `origin` reading res × res wall points, `bins` bins of `bin_m` from path 0."""
    film = {"type": "transient_hdr_film", "width": res, "height": res, "temporal_bins": bins,
            "bin_width_opl": bin_m, "start_opl": 0.0, "rfilter": {"type": "box"}}
    return {"type": "nlos_capture_meter", "sensor_origin": origin, "film": film,
            "sampler": {"type": "independent", "sample_count": spp}}


def laser_spot(mi, x, y, half_m, radiance, opaque):
    """The laser spot: a square area light of side 2 × half_m at (x, y), 0.5 mm in front of the wall. Its
    surface is null (it emits but blocks nothing); an opaque black one blocks the shadow rays that cross
    the medium's boundary near it, which is biased (docs/media-heterogeneous.md)."""
    T = mi.ScalarTransform4f
    bsdf = {"type": "diffuse", "reflectance": 0.0} if opaque else {"type": "null"}
    return {"type": "rectangle", "bsdf": bsdf,
            "to_world": T().translate([x, y, 0.0005]) @ T().scale([half_m, half_m, 1.0]),
            "emitter": {"type": "area", "radiance": radiance}}


def medium_box(mi, centre, half, interior):
    """A null-surfaced cube of half-sizes `half` around `centre` holding the medium `interior`."""
    T = mi.ScalarTransform4f
    return {"type": "cube", "bsdf": {"type": "null"}, "to_world": T().translate(centre) @ T().scale(half),
            "interior": interior}


def render(mi, shapes, max_depth, rr_depth, seed, spp):
    """Renders the scene of `shapes` (name → dict) with INTEGRATOR; returns the transient as an array."""
    import drjit as dr

    scene = mi.load_dict({
        "type": "scene",
        **shapes,
        "integrator": {"type": INTEGRATOR, "camera_unwarp": True, "hide_emitters": True,
                       "temporal_filter": "box", "max_depth": max_depth, "rr_depth": rr_depth},
    })
    _, transient = scene.integrator().render(scene, seed=seed, spp=spp)
    dr.eval(transient)
    return np.array(transient)
