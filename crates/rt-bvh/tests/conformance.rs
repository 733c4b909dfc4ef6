//! The conformance kit for every preset, plus structural validation on the same scenes.

use rt_bvh::{Bvh, BvhParams};
use rt_core::conformance::{self, SCENES};
use rt_core::{Accel, Sphere, Triangle};

rt_core::conformance_tests!(sah, Bvh<Triangle>, BvhParams::sah());
rt_core::conformance_tests!(median, Bvh<Triangle>, BvhParams::median());
rt_core::conformance_tests!(middle, Bvh<Triangle>, BvhParams::middle());

#[test]
fn spheres_sah() {
    conformance::check_random_spheres::<Bvh<Sphere>>(&BvhParams::sah());
}

#[test]
fn validate_passes_on_every_scene_and_preset() {
    for (name, params) in Bvh::<Triangle>::presets() {
        for scene in SCENES {
            let s = conformance::scene(scene);
            let bvh = Bvh::build(&s.triangles, &params);
            if let Err(e) = bvh.validate() {
                panic!("{name} on {scene}: {e}");
            }
        }
    }
}
