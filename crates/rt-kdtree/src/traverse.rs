//! Front-to-back traversal: with a stack (Hapala & Havran's listing), or stackless by restart.
//!
//! Both walk the leaves the ray crosses in order of distance, each with its parametric interval
//! `[t0, t1]`. An interior node costs one subtraction and one multiplication: the distance to its
//! split plane. The near child is the one the direction enters first (by the direction's sign, so
//! it costs no comparison), and each child is visited only if the interval reaches its side of
//! the plane.
//!
//! The closest-hit rule: a primitive may be hit beyond the leaf being tested (it spans several
//! cells), while a closer primitive waits in the next leaf. Such a hit is kept as the best so
//! far, but only a hit inside the current interval ends the walk. Equivalently, a leaf is skipped
//! when it starts beyond the best hit. All interval comparisons allow [`SLAB_FAR_SCALE`] of
//! rounding, as the BVH does, so a primitive tying with the best hit on a cell boundary is still
//! found.

use crate::{KdTree, MAX_DEPTH, Node};
use rt_core::leaf::{self, Seen};
use rt_core::trace::{self, Event, Place, Take};
use rt_core::{Primitive, Ray, RayQuery, SLAB_FAR_SCALE, Stack, Stats};

/// Mailbox slots per ray: the last this many primitives tested are not tested again.
pub(crate) const MAILBOX: usize = 8;

/// Where the ray goes at one interior node.
enum Step {
    /// Only the child the direction enters first (the plane lies beyond the interval).
    Near(usize),
    /// Only the other child (the plane lies before the interval, or behind the origin).
    Far(usize),
    /// Both: the near one for `[t0, t]`, then the far one for `[t, t1]`.
    Both { near: usize, far: usize, t: f32 },
    /// The ray lies in the split plane: both children, each over the whole interval.
    InPlane { near: usize, far: usize },
}

/// The ray's components as arrays, so an axis index does not branch.
#[derive(Clone, Copy)]
struct RayAxes {
    o: [f32; 3],
    inv: [f32; 3],
    /// Bit `a` set where the direction's `a` component has its sign bit set (−0 included): the
    /// child the ray enters first at a plane of axis `a` is `first + (back_bits >> a & 1)`.
    back_bits: usize,
}

impl RayAxes {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        Self {
            o: ray.origin.to_array(),
            inv: ray.inv_dir().to_array(),
            back_bits: ray.dir().is_negative_bitmask() as usize,
        }
    }

    /// The step at interior node `node` for the ray's interval `[t0, t1]`.
    ///
    /// The near child is the one the direction enters first, found from the direction's sign
    /// with no comparison. For a plane ahead of the origin that is the origin's side; for a plane
    /// behind it (`t < 0 <= t0`) the ray only sees the far side, which holds the origin. An origin
    /// in the plane goes by its direction, as the plane's own side rule has it.
    // PERF: AMD Zen 3, one thread, against choosing by a comparison of the origin with the plane
    // (a branch that goes either way for scattered rays): kd ÷ wide BVH in one process, every
    // built-in scene and shared mesh (17), two runs each, new ÷ old per scene, geometric mean
    // (range): incoherent rays 1.13 (0.98–1.26), primary 1.04 (0.92–1.12), shadow 1.03
    // (0.96–1.16). The sign bits sit in one register: read from an array indexed by the axis,
    // the extra load on the path to the next node made primary rays 0.86–0.93x as fast (7
    // paired processes, 3 meshes).
    #[inline(always)]
    fn step(&self, node: &Node, t0: f32, t1: f32) -> Step {
        let a = node.axis();
        let first = node.index();
        let t = (node.split() - self.o[a]) * self.inv[a];
        let s = (self.back_bits >> a) & 1;
        let (near, far) = (first + s, first + 1 - s);
        if t > t1 * SLAB_FAR_SCALE {
            Step::Near(near)
        } else if t * SLAB_FAR_SCALE < t0 {
            Step::Far(far)
        } else if t.is_nan() {
            // Origin in the plane and direction parallel to it: 0 · ∞. Both comparisons above
            // are false for NaN, so this rare case costs nothing on the common path.
            Step::InPlane { near, far }
        } else {
            Step::Both { near, far, t }
        }
    }

    /// The trace's account of `step` taken at interior node `node`.
    fn split_event(&self, node: &Node, step: &Step) -> Event {
        let (a, first) = (node.axis(), node.index());
        // `Near` and `Far` name one child; the other is its sibling.
        let other = |c: usize| if c == first { first + 1 } else { first };
        let (near, far, take) = match *step {
            Step::Near(c) => (c, other(c), Take::Near),
            Step::Far(c) => (other(c), c, Take::Far),
            Step::Both { near, far, .. } => (near, far, Take::Both),
            Step::InPlane { near, far } => (near, far, Take::InPlane),
        };
        Event::Split {
            axis: a,
            pos: node.split(),
            t: (node.split() - self.o[a]) * self.inv[a],
            near: Place::Node(near as u32),
            far: Place::Node(far as u32),
            take,
        }
    }
}

/// How a trace names node `i`.
fn place(nodes: &[Node], i: usize) -> Place {
    if nodes[i].is_leaf() {
        Place::Leaf(i as u32)
    } else {
        Place::Node(i as u32)
    }
}

impl<P: Primitive> KdTree<P> {
    /// Tests a leaf's primitives against `[ray.t_min, q.t_far()]`, offering `q` the hits.
    /// Returns true when the query ends the walk.
    #[inline(always)]
    fn test_leaf<S: Stats, Q: RayQuery, M: Seen>(
        &self,
        node: &Node,
        ray: &Ray,
        q: &mut Q,
        seen: &mut M,
        stats: &mut S,
    ) -> bool {
        let first = node.index();
        let ids = &self.refs[first..first + node.count()];
        leaf::test_primitives(&self.prims, ids, ray, q, seen, true, stats).is_break()
    }

    /// The scene-box interval, or `None` if the ray misses.
    #[inline(always)]
    fn start(&self, ray: &Ray, t_far: f32) -> Option<(f32, f32)> {
        if self.refs.is_empty() {
            return None;
        }
        self.bounds.intersect(ray, t_far)
    }

    /// Stack traversal.
    #[inline(always)]
    pub(crate) fn traverse_stack<S: Stats, Q: RayQuery, M: Seen>(
        &self,
        ray: &Ray,
        q: &mut Q,
        seen: &mut M,
        stats: &mut S,
    ) {
        if let Some((t0, t1)) = self.start(ray, q.t_far()) {
            self.stack_walk(ray, t0, t1, q, seen, stats);
        }
    }

    /// The stack walk from the root over `[t0, t1]`, offering `q` the hits. Returns true when
    /// the query ends the walk.
    ///
    /// Far children are pushed with their intervals; a popped one is skipped if it starts beyond
    /// the best hit. The stack holds at most one entry per level, and the builder bounds the depth
    /// by `MAX_DEPTH`.
    #[inline(always)]
    fn stack_walk<S: Stats, Q: RayQuery, M: Seen>(
        &self,
        ray: &Ray,
        mut t0: f32,
        mut t1: f32,
        q: &mut Q,
        seen: &mut M,
        stats: &mut S,
    ) -> bool {
        let r = RayAxes::new(ray);
        let nodes = &self.nodes[..];
        // The walks' one stack type, whose slots are never initialised. (PERF: neutral here:
        // cachegrind counts 1416 instructions per bunny primary ray in the walk with it and with
        // the zeroed array it replaced, which the compiler had already left uninitialised.)
        let mut stack = Stack::<(u32, f32, f32), MAX_DEPTH>::new();
        let mut current = 0;
        loop {
            stats.node_visit();
            let node = &nodes[current];
            trace::report(stats, || Event::Enter {
                place: place(nodes, current),
                t0,
                t1,
                bounds: None,
            });
            if !node.is_leaf() {
                let step = r.step(node, t0, t1);
                trace::report(stats, || r.split_event(node, &step));
                current = match step {
                    Step::Near(c) | Step::Far(c) => c,
                    Step::Both { near, far, t } => {
                        stack.push((far as u32, t.max(t0), t1));
                        trace::report(stats, || Event::Push {
                            place: place(nodes, far),
                            t: t.max(t0),
                        });
                        t1 = t.min(t1);
                        near
                    }
                    Step::InPlane { near, far } => {
                        stack.push((far as u32, t0, t1));
                        trace::report(stats, || Event::Push {
                            place: place(nodes, far),
                            t: t0,
                        });
                        near
                    }
                };
                continue;
            }
            if self.test_leaf(node, ray, q, seen, stats) {
                return true;
            }
            loop {
                let Some((index, a0, a1)) = stack.pop() else {
                    trace::report(stats, || Event::Note("stack empty: done"));
                    return false;
                };
                let skipped = a0 > q.t_far() * SLAB_FAR_SCALE;
                trace::report(stats, || Event::Pop {
                    place: place(nodes, index as usize),
                    t: a0,
                    skipped,
                });
                if !skipped {
                    (current, t0, t1) = (index as usize, a0, a1);
                    break;
                }
            }
        }
    }

    /// Stackless traversal by kd-restart (Foley & Sugerman 2005) with push-down (Horn et al.
    /// 2007): after a leaf ending at `t1` without a valid hit, descend again from the top with
    /// the interval starting at `t1`. The descent starts at the deepest node found so far whose
    /// cell holds the whole rest of the ray (push-down), not always at the root.
    ///
    /// At a restart the exit plane of the previous leaf lies exactly at `t0`, and the walk goes to
    /// its far side. Restart cannot visit a leaf the ray only touches at one point (where it
    /// passes through an edge or corner of cells): when a descent meets a plane within rounding of
    /// `t0` (other than that exit plane) or of `t1`, or the ray lies in a split plane, the ray
    /// finishes with [`stack_walk`](Self::stack_walk), which visits both sides. Such rays need
    /// coordinates that coincide to within 2⁻¹⁶, so they are rare, and the answer stays exact.
    #[inline(always)]
    pub(crate) fn traverse_restart<S: Stats, Q: RayQuery, M: Seen>(
        &self,
        ray: &Ray,
        q: &mut Q,
        seen: &mut M,
        stats: &mut S,
    ) {
        let Some((mut t0, t_end)) = self.start(ray, q.t_far()) else {
            return;
        };
        let r = RayAxes::new(ray);
        let nodes = &self.nodes[..];
        let mut top = 0;
        let mut exit_node = usize::MAX;
        let mut restarted = false;
        loop {
            let mut current = top;
            let mut t1 = t_end;
            let mut branched = false;
            let mut leaf_exit = usize::MAX;
            loop {
                stats.node_visit();
                let node = &nodes[current];
                trace::report(stats, || Event::Enter {
                    place: place(nodes, current),
                    t0,
                    t1,
                    bounds: None,
                });
                if node.is_leaf() {
                    break;
                }
                let step = r.step(node, t0, t1);
                trace::report(stats, || r.split_event(node, &step));
                let next = match step {
                    Step::Near(c) => c,
                    Step::Far(c) => c,
                    Step::Both { far, .. } if current == exit_node => {
                        trace::report(stats, || {
                            Event::Note("the last leaf's exit plane: its far side")
                        });
                        far
                    }
                    // A plane within rounding of either end of the interval means a leaf
                    // touched at one point: the near one at a restart, or the far one, which the
                    // next restart would skip.
                    Step::Both { near, t, .. }
                        if (!restarted || t > t0 * SLAB_FAR_SCALE) && t * SLAB_FAR_SCALE < t1 =>
                    {
                        branched = true;
                        if t < t1 {
                            t1 = t;
                            leaf_exit = current;
                        }
                        near
                    }
                    Step::Both { .. } | Step::InPlane { .. } => {
                        trace::report(stats, || {
                            Event::Note("a plane at the interval's end: finish with the stack walk")
                        });
                        self.stack_walk(ray, t0, t_end, q, seen, stats);
                        return;
                    }
                };
                if !branched {
                    top = next;
                }
                current = next;
            }
            if self.test_leaf(&nodes[current], ray, q, seen, stats)
                || t1 >= t_end
                || t1 > q.t_far() * SLAB_FAR_SCALE
            {
                return;
            }
            t0 = t1;
            exit_node = leaf_exit;
            restarted = true;
            trace::report(stats, || {
                Event::Note("no hit in this leaf: restart from the top node")
            });
        }
    }
}
