//! Following moving primitives: every box updated bottom-up instead of a rebuild
//! ([`Refit`]), and the SAH cost that tells when the refitted tree has drifted far enough from
//! a fresh build's to rebuild.

use crate::node::{ChildRef, Node, TriPack, WIDTH, WideNode};
use crate::{Bvh, Input, Items, Layout, Leaves, PACK, Tree, Wide};
use rt_core::glam::Vec3;
use rt_core::par;
use rt_core::{Aabb, Geometry, Primitive, Refit, RefitError, Triangle, TriangleTest};
use std::collections::HashMap;

/// Refits over at least this many primitives run on rayon's threads (when allowed): the
/// builder's threshold for a parallel build, reused and not tuned for refits.
const PAR_REFIT_MIN: usize = 1 << 14;
/// Primitives per task of the parallel validity count.
const REFIT_CHUNK: usize = 1 << 12;

/// A triangle's vertices as bits: equal keys are bit-identical copies.
type Key = [[u32; 3]; 3];

fn key<P: Primitive>(p: &P) -> Option<Key> {
    p.as_triangle()
        .map(|(t, _)| [t.v0, t.v1, t.v2].map(|v| v.to_array().map(f32::to_bits)))
}

/// The primitives of `geometry` that `bvh`, just built over it, does not store: the invalid
/// ones, and bit-identical copies of a stored triangle with the copy stored. One pass over a
/// bitmap of the input, made only when the tree stores fewer primitives than the input has.
pub(crate) fn left_out<P: Primitive, G: Geometry<Prim = P> + ?Sized>(
    bvh: &Bvh<P>,
    geometry: &G,
) -> Input {
    let len = geometry.len();
    let considered = len.min(u32::MAX as usize);
    let mut input = Input {
        len,
        ..Input::default()
    };
    if bvh.stored == considered {
        return input;
    }
    let mut stored = vec![false; considered];
    bvh.for_each_stored(|id| stored[id as usize] = true);
    let mut twins: Option<HashMap<Key, u32>> = None;
    for (i, _) in stored.iter().enumerate().filter(|(_, s)| !**s) {
        let p = geometry.prim(i);
        let twin = p.is_valid().then(|| key(&p)).flatten().and_then(|k| {
            let twins = twins.get_or_insert_with(|| {
                let mut map = HashMap::new();
                bvh.for_each_stored(|id| {
                    if let Some(k) = key(&geometry.prim(id as usize)) {
                        map.entry(k).or_insert(id);
                    }
                });
                map
            });
            twins.get(&k).copied()
        });
        match twin {
            Some(of) => input.copies.push((i as u32, of)),
            // Invalid, or (never, as the builder leaves out only copies) a valid primitive
            // without a stored twin: recorded as invalid, so a refit asks for a rebuild.
            None => input.invalid.push(i as u32),
        }
    }
    input.twins = input.copies.iter().map(|&(copy, of)| (of, copy)).collect();
    input.twins.sort_unstable();
    input
}

impl<P: Primitive> Bvh<P> {
    /// Calls `f` with the input index of every primitive the tree stores.
    fn for_each_stored(&self, mut f: impl FnMut(u32)) {
        if self.pack_test().is_some() {
            for pack in self.packs() {
                pack.ids
                    .iter()
                    .filter(|&&id| id != u32::MAX)
                    .for_each(|&id| f(id));
            }
        } else {
            self.primitive_ids().iter().for_each(|&id| f(id));
        }
    }

    /// The tree's cost under the surface area heuristic its builder minimizes: for a ray
    /// through the root's box, the expected node visits times the traversal cost plus the
    /// expected primitive tests (packs of four, in the wide tree's packed leaves) times the
    /// intersection cost, each node or leaf entered with the probability `area / root area`
    /// (see [`rt_core::predicted_cost`]). 0 for an empty tree.
    ///
    /// `O(nodes)`, no allocation: cheap next to a build. After a [`refit`](Refit::refit) it
    /// grows as the primitives move apart from where the tree was built for; divided by a
    /// fresh build's (or, without building, by [`built_sah_cost`](Bvh::built_sah_cost)) it
    /// says how much worse the refitted tree has become, and so when to rebuild.
    ///
    /// ```
    /// use rt_bvh::Bvh;
    /// use rt_core::{Accel, Refit, Triangle, glam::Vec3};
    /// let tri = |x: f32| Triangle::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 0.0, 0.0), Vec3::new(x, 1.0, 0.0));
    /// let mut bvh = Bvh::build(&(0..64).map(|i| tri(i as f32 * 2.0)).collect::<Vec<_>>(), &Default::default());
    /// // The triangles swap places: every leaf box now spans the whole row.
    /// let moved: Vec<Triangle> = (0..64).map(|i| tri(if i % 2 == 0 { i as f32 } else { 126.0 - i as f32 })).collect();
    /// bvh.refit(&moved).unwrap();
    /// let fresh = Bvh::build(&moved, &Default::default());
    /// assert!(bvh.sah_cost() > 1.5 * fresh.sah_cost());
    /// ```
    pub fn sah_cost(&self) -> f64 {
        let area = self.root_bounds().surface_area() as f64;
        if !(area > 0.0 && area.is_finite()) {
            return 0.0;
        }
        let (traversal, intersection) = (self.costs.0 as f64, self.costs.1 as f64);
        let p = |b: &Aabb| (b.surface_area() as f64 / area).clamp(0.0, 1.0);
        match self.layout() {
            Layout::Binary => self
                .nodes()
                .iter()
                .map(|n| {
                    if n.is_leaf() {
                        intersection * n.count as f64 * p(&n.bounds)
                    } else {
                        traversal * p(&n.bounds)
                    }
                })
                .sum(),
            Layout::Wide => {
                let children = self.wide_nodes().iter().flat_map(|n| {
                    (0..WIDTH)
                        .map(move |i| (n.child(i), n.child_bounds(i)))
                        .filter(|(c, _)| *c != ChildRef::EMPTY)
                });
                let cost: f64 = children
                    .map(|(c, b)| {
                        if c.is_leaf() {
                            intersection * c.items().len() as f64 * p(&b)
                        } else {
                            traversal * p(&b)
                        }
                    })
                    .sum();
                traversal + cost
            }
        }
    }

    /// [`sah_cost`](Bvh::sah_cost) when the tree was built (refits do not change it).
    pub fn built_sah_cost(&self) -> f64 {
        self.built_cost
    }

    /// Whether `geometry` can be followed: the same count, every stored primitive still valid
    /// and of the kind its leaf stores, every left-out one still invalid or still a copy.
    ///
    /// PERF: validity is counted in input order, which streams through the geometry and splits
    /// into parallel chunks, instead of looked up per stored primitive in tree order, which
    /// jumps about it: on the bunny (69,451 triangles, a wave's frames, timed inside the
    /// refit) the check took 0.50 ms the second way on one thread and 0.15 ms this way on
    /// two; the whole refit 1.4 ms and 0.68 ms. The count settles it:
    /// the left-out invalid ones are checked one by one, so the valid ones can only be the
    /// stored ones and their copies, and if as many are valid as before, all of those are.
    fn check_refit<G: Geometry<Prim = P> + ?Sized>(&self, geometry: &G) -> Result<(), RefitError> {
        let len = geometry.len();
        if len != self.input.len {
            return Err(RefitError::CountChanged {
                built: self.input.len,
                now: len,
            });
        }
        if let Some(&prim) = self
            .input
            .invalid
            .iter()
            .find(|&&i| geometry.prim(i as usize).is_valid())
        {
            return Err(RefitError::ValidityChanged { prim });
        }
        // Valid primitives in `range`, and the first of them no longer of the packs' kind.
        let scan = |range: std::ops::Range<usize>| {
            let mut valid = 0usize;
            let mut kind = None;
            for i in range {
                let p = geometry.prim(i);
                if p.is_valid() {
                    valid += 1;
                    if kind.is_none()
                        && self.pack_test().is_some()
                        && p.as_triangle().map(|(_, t)| t) != self.pack_test()
                    {
                        kind = Some(i as u32);
                    }
                }
            }
            (valid, kind)
        };
        let considered = len.min(u32::MAX as usize);
        let (valid, kind) = if self.parallel_refit(considered) {
            par::map_range(0..considered.div_ceil(REFIT_CHUNK), |c| {
                scan(c * REFIT_CHUNK..((c + 1) * REFIT_CHUNK).min(considered))
            })
            .into_iter()
            .fold((0, None), |(va, ka), (vb, kb)| (va + vb, ka.or(kb)))
        } else {
            scan(0..considered)
        };
        if let Some(prim) = kind {
            return Err(RefitError::KindChanged { prim });
        }
        if valid != self.valid {
            // One of the stored primitives or their copies became invalid: name the first.
            let mut first = None;
            self.for_each_stored(|id| {
                if first.is_none() && !geometry.prim(id as usize).is_valid() {
                    first = Some(id);
                }
            });
            let copy = || {
                self.input
                    .copies
                    .iter()
                    .map(|&(c, _)| c)
                    .find(|&c| !geometry.prim(c as usize).is_valid())
            };
            let prim = first.or_else(copy).unwrap_or(u32::MAX);
            return Err(RefitError::ValidityChanged { prim });
        }
        if let Some(&(prim, copy_of)) = self.input.copies.iter().find(|&&(c, of)| {
            let k = key(&geometry.prim(c as usize));
            k.is_none() || k != key(&geometry.prim(of as usize))
        }) {
            return Err(RefitError::CopiesDiverged { prim, copy_of });
        }
        Ok(())
    }

    /// Whether a refit over `n` primitives runs on rayon's threads.
    fn parallel_refit(&self, n: usize) -> bool {
        self.parallel && n >= PAR_REFIT_MIN && par::threads() > 1
    }

    /// The binary tree, children after their parents: leaves re-read their primitives, interior
    /// nodes take the union of their two children.
    fn refit_binary<G: Geometry<Prim = P> + ?Sized>(
        nodes: &mut [Node],
        items: &mut Items<P>,
        geometry: &G,
    ) {
        if items.ids.is_empty() {
            return; // the one never-hit node of an empty tree
        }
        for i in (0..nodes.len()).rev() {
            let node = nodes[i];
            nodes[i].bounds = if node.is_leaf() {
                let mut b = Aabb::EMPTY;
                for k in node.prim_range() {
                    items.prims[k] = geometry.prim(items.ids[k] as usize);
                    b = b.union(items.prims[k].bounds());
                }
                b
            } else {
                nodes[i + 1].bounds.union(nodes[node.index as usize].bounds)
            };
        }
    }

    /// The wide tree: the triangle packs re-read from the geometry (on rayon's threads when
    /// `parallel` says so), then the nodes, children (higher indices) before their parents: a
    /// leaf lane takes the box of its packs (or re-reads its primitives), a node lane the union
    /// of the child node's lanes.
    fn refit_wide<G: Geometry<Prim = P> + ?Sized>(
        wide: &mut Wide<P>,
        geometry: &G,
        parallel: impl Fn(usize) -> bool,
    ) {
        if let Leaves::Packs { packs, test } = &mut wide.leaves {
            let test = *test;
            let repack = |pack: &mut TriPack| {
                let mut tris = [(Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO), 0); PACK];
                let n = pack.len();
                for (slot, &id) in tris.iter_mut().zip(&pack.ids[..n]) {
                    let (t, _) = geometry
                        .prim(id as usize)
                        .as_triangle()
                        .expect("checked before refitting");
                    *slot = (t, id);
                }
                *pack = TriPack::new(&tris[..n], test);
            };
            if parallel(packs.len() * PACK) {
                par::for_each_mut(packs, 256, repack);
            } else {
                packs.iter_mut().for_each(repack);
            }
        }
        for i in (0..wide.nodes.len()).rev() {
            let (head, tail) = wide.nodes.split_at_mut(i + 1);
            let node = &mut head[i];
            for lane in 0..WIDTH {
                let c = node.child(lane);
                if c == ChildRef::EMPTY {
                    continue;
                }
                let b = if !c.is_leaf() {
                    node_box(&tail[c.index() - i - 1])
                } else {
                    match &mut wide.leaves {
                        // The packs hold the vertices themselves.
                        Leaves::Packs {
                            packs,
                            test: TriangleTest::Watertight,
                        } => packs[c.items()]
                            .iter()
                            .fold(Aabb::EMPTY, |b, p| b.union(pack_box(p))),
                        // The packs hold edges, whose sums with `v0` may round: the box comes
                        // from the primitives, as the build's did.
                        Leaves::Packs {
                            packs,
                            test: TriangleTest::MollerTrumbore,
                        } => packs[c.items()]
                            .iter()
                            .flat_map(|p| p.ids[..p.len()].iter())
                            .fold(Aabb::EMPTY, |b, &id| {
                                b.union(geometry.prim(id as usize).bounds())
                            }),
                        Leaves::Items(items) => {
                            let mut b = Aabb::EMPTY;
                            for k in c.items() {
                                items.prims[k] = geometry.prim(items.ids[k] as usize);
                                b = b.union(items.prims[k].bounds());
                            }
                            b
                        }
                    }
                };
                let rows = [b.min, b.max].map(|v| v.to_array());
                for (axis, row) in node.bounds.iter_mut().enumerate() {
                    row[lane] = rows[axis / 3][axis % 3];
                }
            }
        }
    }
}

/// The box around a watertight pack's triangles (its used lanes hold the vertices).
fn pack_box(p: &TriPack) -> Aabb {
    let n = p.len();
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for lane in 0..n {
        for v in 0..3 {
            let x = Vec3::new(
                p.rows[3 * v][lane],
                p.rows[3 * v + 1][lane],
                p.rows[3 * v + 2][lane],
            );
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    Aabb::new(lo, hi)
}

/// The union of a wide node's used lanes.
fn node_box(node: &WideNode) -> Aabb {
    (0..WIDTH)
        .filter(|&i| node.child(i) != ChildRef::EMPTY)
        .fold(Aabb::EMPTY, |b, i| b.union(node.child_bounds(i)))
}

/// Refits in `O(N)` with no allocation: checks first that the primitives can be followed (the
/// same count; every stored one still valid and, in triangle packs, still a triangle; the ones
/// left out still invalid or still copies), then re-reads every leaf's primitives and updates
/// every box bottom-up. The tree's shape, and so its SAH quality, stays what the build chose
/// ([`Bvh::sah_cost`] measures the drift).
impl<P: Primitive> Refit for Bvh<P> {
    fn refit<G: Geometry<Prim = P> + ?Sized>(&mut self, geometry: &G) -> Result<(), RefitError> {
        self.check_refit(geometry)?;
        let parallel = self.parallel;
        match &mut self.tree {
            Tree::Binary { nodes, items } => Self::refit_binary(nodes, items, geometry),
            Tree::Wide(wide) => Self::refit_wide(wide, geometry, |n| {
                parallel && n >= PAR_REFIT_MIN && par::threads() > 1
            }),
        }
        Ok(())
    }
}
