//! Near-child-first iterative traversal, shared by closest-hit and any-hit queries.

use crate::{Bvh, MAX_DEPTH};
use rt_core::{Hit, Primitive, Ray, SLAB_FAR_SCALE, Stats};

impl<P: Primitive> Bvh<P> {
    /// The traversal core. `ANY = false` finds the closest hit; `ANY = true` returns the first
    /// hit found (its `t` need not be the smallest).
    ///
    /// At an interior node both children's boxes are tested against `[t_min, best_t]`; the
    /// nearer child is visited next and the farther one is pushed with its entry distance, and
    /// skipped when popped if a hit closer than that entry has been found meanwhile
    /// (front-to-back traversal; the comparison allows [`SLAB_FAR_SCALE`] of rounding, as the box
    /// test does, so a primitive tying with the best hit is still found). The stack holds at most one entry per tree level, and the
    /// builder bounds the depth by `MAX_DEPTH`, so a fixed array suffices.
    #[inline(always)]
    pub(crate) fn traverse<S: Stats, const ANY: bool>(
        &self,
        ray: &Ray,
        stats: &mut S,
    ) -> Option<Hit> {
        let nodes = &self.nodes[..];
        let mut best = Hit {
            prim: u32::MAX,
            t: ray.t_max,
            u: 0.0,
            v: 0.0,
        };
        if self.ids.is_empty() || nodes[0].bounds.intersect(ray, best.t).is_none() {
            return None;
        }
        let mut stack = [(0u32, 0.0f32); MAX_DEPTH];
        let mut sp = 0;
        let mut current = 0usize;
        loop {
            stats.node_visit();
            let node = &nodes[current];
            if node.is_leaf() {
                // PERF: one bounds check per leaf instead of two per primitive: bunny primary rays
                // 8.76 -> 9.20 Mrays/s single-threaded (`cargo bench -p rt-benches --bench trace`).
                let range = node.prim_range();
                for (prim, &id) in self.prims[range.clone()].iter().zip(&self.ids[range]) {
                    stats.prim_test();
                    if ANY {
                        if prim.occludes(ray, best.t) {
                            return Some(Hit {
                                prim: id,
                                t: f32::NAN,
                                u: 0.0,
                                v: 0.0,
                            });
                        }
                    } else if let Some(h) = prim.intersect(ray, best.t)
                        && Hit::beats(h.t, id, best.t, best.prim)
                    {
                        best = Hit {
                            prim: id,
                            t: h.t,
                            u: h.u,
                            v: h.v,
                        };
                    }
                }
            } else {
                let (a, b) = (current + 1, node.index as usize);
                let ta = nodes[a].bounds.entry(ray, best.t);
                let tb = nodes[b].bounds.entry(ray, best.t);
                let (near, t_near, far, t_far) = if ta <= tb {
                    (a, ta, b, tb)
                } else {
                    (b, tb, a, ta)
                };
                if t_near != f32::INFINITY {
                    if t_far != f32::INFINITY {
                        stack[sp] = (far as u32, t_far);
                        sp += 1;
                    }
                    current = near;
                    continue;
                }
            }
            // Pop the next subtree that can still hold a hit no farther than the best so far.
            loop {
                if sp == 0 {
                    return (best.prim != u32::MAX).then_some(best);
                }
                sp -= 1;
                let (index, t_entry) = stack[sp];
                if t_entry <= best.t * SLAB_FAR_SCALE {
                    current = index as usize;
                    break;
                }
            }
        }
    }
}
