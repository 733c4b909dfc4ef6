//! Built-in animations: triangles moved frame by frame, for refitting against rebuilding
//! (`cargo xtask animate`) and for the refit kit.

use glam::{Quat, Vec3};
use rt_core::{Aabb, Rng, Triangle};

/// The box around the valid triangles and its largest side (1 for an empty or flat-to-a-point
/// scene), which sets the size of every motion.
fn extent(tris: &[Triangle]) -> (Aabb, f32) {
    let bounds = rt_core::valid_bounds(tris.iter());
    let e = if bounds.is_empty() {
        1.0
    } else {
        bounds.extent().max_element()
    };
    (bounds, if e > 0.0 && e.is_finite() { e } else { 1.0 })
}

/// The triangles bent by a wave travelling through them: at `phase` (radians; one period is
/// 2π) every vertex moves by a smooth function of where it is, at most a tenth of the scene's
/// extent, and not at all at phase 0. Shared vertices stay shared and bit-identical copies stay copies: a mesh deforming,
/// as a skinned character or cloth does, with every triangle near where it was.
pub fn wave(tris: &[Triangle], phase: f32) -> Vec<Triangle> {
    let (_, extent) = extent(tris);
    let k = std::f32::consts::TAU / extent;
    // A travelling wave less the wave at rest, so phase 0 leaves every vertex in place.
    let w = |a: f32, phase: f32| (a + phase).sin() - a.sin();
    let bend = |v: Vec3| {
        v + 0.05
            * extent
            * Vec3::new(
                w(k * v.y, phase),
                w(k * v.z, 2.0 * phase),
                w(k * v.x, 3.0 * phase),
            )
    };
    tris.iter()
        .map(|t| Triangle::new(bend(t.v0), bend(t.v1), bend(t.v2)))
        .collect()
}

/// The triangles of an explosion at `time` (0: where they are; 1: flown one to two times the
/// scene's extent, accelerating from rest): each moves rigidly, outwards from the centre of the scene's box in a
/// direction and at a speed drawn from its own vertices' bits and `seed` (so bit-identical
/// copies move together), spinning about its centroid. Neighbours part ways, so a tree built
/// for the first frame fits the later ones worse and worse.
pub fn explode(tris: &[Triangle], time: f32, seed: u64) -> Vec<Triangle> {
    let (bounds, extent) = extent(tris);
    let center = if bounds.is_empty() {
        Vec3::ZERO
    } else {
        bounds.center()
    };
    tris.iter()
        .map(|t| {
            let bits = [t.v0, t.v1, t.v2].map(|v| v.to_array().map(f32::to_bits));
            let h = bits
                .iter()
                .flatten()
                .fold(seed ^ 0xcbf2_9ce4_8422_2325, |h, &b| {
                    (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
                });
            let mut rng = Rng::new(h);
            let c = (t.v0 + t.v1 + t.v2) / 3.0;
            let out = ((c - center) / extent + 0.5 * rng.unit_vector()).normalize_or(Vec3::Y);
            let speed = 1.0 + rng.f32();
            let spin = Quat::from_axis_angle(rng.unit_vector(), time * 6.0 * rng.f32());
            // From rest, at constant acceleration: slow at first, so the frames show the tree
            // degrading gradually rather than all at once.
            let shift = time * time * extent * speed * out;
            let m = |v: Vec3| c + shift + spin * (v - c);
            Triangle::new(m(t.v0), m(t.v1), m(t.v2))
        })
        .collect()
}

/// A built-in animation, as `cargo xtask animate --animation` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Animation {
    /// [`wave`], one period over the frames.
    Wave,
    /// [`explode`], from time 0 to 1 over the frames.
    Explode,
}

impl Animation {
    /// Every animation, with its name.
    pub const ALL: [(&'static str, Animation); 2] =
        [("wave", Animation::Wave), ("explode", Animation::Explode)];

    /// Frame `frame` of `frames` (frame 0 is `tris` itself).
    pub fn frame(self, tris: &[Triangle], frame: usize, frames: usize) -> Vec<Triangle> {
        let t = frame as f32 / frames.max(1) as f32;
        match self {
            Animation::Wave => wave(tris, std::f32::consts::TAU * t),
            Animation::Explode => explode(tris, t, 1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_zero_is_the_scene_and_later_frames_move() {
        let tris = crate::scenes::builtin("teapot").unwrap().triangles();
        for (_, a) in Animation::ALL {
            let first = a.frame(&tris, 0, 10);
            let moved = a.frame(&tris, 5, 10);
            let dist = |x: &[Triangle]| {
                x.iter()
                    .zip(&tris)
                    .map(|(a, b)| (a.v0 - b.v0).length())
                    .fold(0.0f32, f32::max)
            };
            assert!(dist(&first) < 1e-3, "{a:?}: {}", dist(&first));
            assert!(dist(&moved) > 0.05, "{a:?}: {}", dist(&moved));
        }
        let (_, before) = extent(&tris);
        let (_, after) = extent(&explode(&tris, 1.0, 1));
        assert!(after > 3.0 * before, "{after} against {before}");
    }
}
