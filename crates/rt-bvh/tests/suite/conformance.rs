//! The conformance kit for every preset and, for the wide layout, every set of kernels (SSE2
//! and the portable ones are forced here, so the fallbacks are tested on every CI run, AVX2 or
//! not), plus structural validation on the same scenes.

use rt_bvh::{Ablation, Bvh, BvhParams, Kernels};
use rt_conformance::SCENES;
use rt_core::{Accel, Sphere, Triangle};
use rt_simd::Isa;

/// SSE2 where the target has it, else the portable kernels.
fn sse2() -> Kernels {
    Kernels::Simd(Isa::sse2().unwrap_or(Isa::Portable))
}

fn wide_with(kernels: Kernels) -> BvhParams {
    BvhParams {
        kernels: Some(kernels),
        ..BvhParams::wide()
    }
}

rt_conformance::conformance_tests!(wide, Bvh<Triangle>, BvhParams::wide());
rt_conformance::conformance_tests!(wide_sse2, Bvh<Triangle>, wide_with(sse2()));
rt_conformance::conformance_tests!(
    wide_portable,
    Bvh<Triangle>,
    wide_with(Kernels::Simd(Isa::Portable))
);
rt_conformance::conformance_tests!(wide_scalar, Bvh<Triangle>, wide_with(Kernels::Scalar));
rt_conformance::conformance_tests!(
    wide_sequential,
    Bvh<Triangle>,
    BvhParams {
        parallel: false,
        ..BvhParams::wide()
    }
);
rt_conformance::conformance_tests!(
    wide_unsorted_closest_any,
    Bvh<Triangle>,
    BvhParams {
        ablation: Ablation {
            sort_children: false,
            any_hit_path: false,
            stream_walk: false,
        },
        ..BvhParams::wide()
    }
);
rt_conformance::conformance_tests!(
    wide_stream,
    Bvh<Triangle>,
    BvhParams {
        ablation: Ablation {
            stream_walk: true,
            ..Ablation::default()
        },
        ..BvhParams::wide()
    }
);
rt_conformance::conformance_tests!(binary, Bvh<Triangle>, BvhParams::sah());
rt_conformance::conformance_tests!(median, Bvh<Triangle>, BvhParams::median());
rt_conformance::conformance_tests!(middle, Bvh<Triangle>, BvhParams::middle());
rt_conformance::conformance_tests!(reinserted, Bvh<Triangle>, BvhParams::reinserted());
rt_conformance::conformance_tests!(
    binary_reinserted,
    Bvh<Triangle>,
    BvhParams {
        reinsertion_passes: 3,
        ..BvhParams::sah()
    }
);

#[test]
fn spheres() {
    rt_conformance::check_random_spheres::<Bvh<Sphere>>(&BvhParams::sah());
    // Spheres are no triangles: the wide tree keeps them in primitive leaves.
    rt_conformance::check_random_spheres::<Bvh<Sphere>>(&BvhParams::wide());
    rt_conformance::check_random_spheres::<Bvh<Sphere>>(&wide_with(Kernels::Simd(Isa::Portable)));
    rt_conformance::check_random_spheres::<Bvh<Sphere>>(&wide_with(sse2()));
}

#[test]
fn validate_passes_on_every_scene_and_preset() {
    for (name, params) in Bvh::<Triangle>::presets() {
        for scene in SCENES {
            let s = rt_conformance::scene(scene);
            let bvh = Bvh::build(&s.triangles, &params);
            if let Err(e) = bvh.validate() {
                panic!("{name} on {scene}: {e}");
            }
        }
    }
}
