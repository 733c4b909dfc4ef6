//! Structural checks of a built tree.

use crate::node::{ChildRef, Node, PACK, TriPack, WIDTH};
use crate::{Bvh, Layout, MAX_DEPTH};
use rt_core::glam::Vec3;
use rt_core::{Aabb, Primitive, TriangleTest, ValidationError};
use std::sync::atomic::{AtomicU64, Ordering};

impl<P: Primitive> Bvh<P> {
    /// Checks the tree's invariants.
    ///
    /// Binary layout:
    /// - the nodes form one depth-first tree (first child right after its parent, second child
    ///   after the first child's subtree) no deeper than the traversal stack;
    /// - every kept primitive is in exactly one leaf, and the primitive ids are distinct (as many
    ///   as the valid primitives but for bit-identical copies of a triangle, which are left out);
    /// - every child box lies inside its parent's box, and every primitive's box inside its
    ///   leaf's box.
    ///
    /// Wide layout:
    /// - every node is reached exactly once from the root, through children of higher index, no
    ///   deeper than the traversal stack; used lanes come first, unused ones hold the empty box;
    /// - each node's children's boxes lie inside the box its parent stores for it, and each
    ///   leaf's triangles (or primitives) inside the leaf's box;
    /// - every pack (or primitive slot) is in exactly one leaf; packs fill their lanes from the
    ///   first, unused lanes hold NaN; the triangle ids are distinct and as many as the valid
    ///   primitives but for bit-identical copies.
    ///
    /// # Errors
    /// The first broken invariant.
    pub fn validate(&self) -> Result<(), ValidationError> {
        self.validated_ids().map(|_| ())
    }

    /// [`validate`](Bvh::validate), giving back the stored ids as one bit per input index.
    pub(crate) fn validated_ids(&self) -> Result<Vec<u64>, ValidationError> {
        match self.layout() {
            Layout::Binary => self.validate_binary(),
            Layout::Wide => self.validate_wide(),
        }
    }

    fn validate_binary(&self) -> Result<Vec<u64>, ValidationError> {
        let err = |node: Option<usize>, message: String| Err(ValidationError { node, message });
        let nodes = self.nodes();
        let n = self.primitives().len();
        if self.primitive_ids().len() != n {
            return err(
                None,
                format!("{} primitives but {} ids", n, self.primitive_ids().len()),
            );
        }
        if n == 0 {
            // The builder's one never-entered node, and nothing a walk could follow.
            let empty = Node {
                bounds: Aabb::EMPTY,
                index: 0,
                count: 0,
                axis: 0,
                pad: 0,
            };
            return if nodes == [empty] {
                self.check_counts(0, 0)?;
                Ok(vec![0; self.input.len.div_ceil(64)])
            } else {
                err(None, "an empty tree must be its one empty node".into())
            };
        }
        let mut covered = vec![false; n];
        let mut stack = vec![(0usize, 0usize)];
        let mut next_expected = 0usize;
        let (mut leaves, mut deepest) = (0usize, 0usize);
        while let Some((i, depth)) = stack.pop() {
            if i != next_expected {
                return err(
                    Some(i),
                    format!("not in depth-first order (expected node {next_expected})"),
                );
            }
            next_expected += 1;
            if depth >= MAX_DEPTH {
                return err(
                    Some(i),
                    format!("depth {depth} exceeds the traversal stack ({MAX_DEPTH})"),
                );
            }
            let node = nodes.get(i).ok_or(ValidationError {
                node: Some(i),
                message: "index out of range".into(),
            })?;
            deepest = deepest.max(depth);
            if node.is_leaf() {
                leaves += 1;
                let range = node.prim_range();
                if range.end > n {
                    return err(Some(i), format!("leaf range {range:?} past {n} primitives"));
                }
                for k in range {
                    if std::mem::replace(&mut covered[k], true) {
                        return err(Some(i), format!("primitive slot {k} is in two leaves"));
                    }
                    if !node.bounds.contains(&self.primitives()[k].bounds()) {
                        return err(
                            Some(i),
                            format!("primitive slot {k} sticks out of its leaf box"),
                        );
                    }
                }
            } else {
                if node.axis > 2 {
                    return err(
                        Some(i),
                        format!("split axis {} is not 0, 1 or 2", node.axis),
                    );
                }
                let (a, b) = (i + 1, node.index as usize);
                if b <= a || b >= nodes.len() {
                    return err(Some(i), format!("second child {b} out of order or range"));
                }
                for c in [a, b] {
                    if !node.bounds.contains(&nodes[c].bounds) {
                        return err(
                            Some(i),
                            format!("child {c}'s box is not inside its parent's"),
                        );
                    }
                }
                stack.push((b, depth + 1));
                stack.push((a, depth + 1));
            }
        }
        if next_expected != nodes.len() {
            return err(
                None,
                format!("{} nodes reachable of {}", next_expected, nodes.len()),
            );
        }
        if let Some(k) = covered.iter().position(|c| !c) {
            return err(None, format!("primitive slot {k} is in no leaf"));
        }
        self.check_counts(leaves, deepest)?;
        distinct_ids(
            self.primitive_ids().iter().copied(),
            self.input.len,
            self.stored,
            self.valid,
        )
    }

    /// What is wrong with the wide leaf holding `items` in box `b`, if anything: a pack with a
    /// gap or a filled unused lane, or an item sticking out of the box.
    fn leaf_fault(&self, items: std::ops::Range<usize>, b: &Aabb) -> Option<String> {
        for k in items {
            if let Some(test) = self.pack_test() {
                let pack = &self.packs()[k];
                let n = pack.len();
                if pack.ids[..n].contains(&u32::MAX)
                    || pack.rows.iter().any(|r| r[n..].iter().any(|x| !x.is_nan()))
                {
                    return Some(format!("pack {k} has a gap or a filled unused lane"));
                }
                if !pack_inside(pack, n, test, b) {
                    return Some(format!("item {k} sticks out of its leaf box"));
                }
            } else if !b.contains(&self.primitives()[k].bounds()) {
                return Some(format!("item {k} sticks out of its leaf box"));
            }
        }
        None
    }

    /// Checks the leaf count and depth the tree reports against what a walk found. A wide
    /// tree reports the depth of the binary tree it was collapsed from, at least one less than
    /// its own leaves' (`deepest` is then a lower bound).
    fn check_counts(&self, leaves: usize, deepest: usize) -> Result<(), ValidationError> {
        let depth_ok = match self.layout() {
            Layout::Binary => deepest == self.max_depth,
            Layout::Wide => deepest <= self.max_depth + 1,
        };
        if leaves == self.leaves && depth_ok {
            Ok(())
        } else {
            Err(ValidationError::new(format!(
                "stats say {} leaves and depth {}; the tree has {leaves} and {deepest}",
                self.leaves, self.max_depth
            )))
        }
    }

    fn validate_wide(&self) -> Result<Vec<u64>, ValidationError> {
        let err = |node: Option<usize>, message: String| Err(ValidationError { node, message });
        let nodes = self.wide_nodes();
        if nodes.is_empty() {
            return if self.valid == 0
                && self.stored == 0
                && self.packs().is_empty()
                && self.primitives().is_empty()
                && self.primitive_ids().is_empty()
            {
                self.check_counts(0, 0)?;
                Ok(vec![0; self.input.len.div_ceil(64)])
            } else {
                err(None, "no nodes but primitives were kept".into())
            };
        }
        let packed = self.pack_test().is_some();
        let items = if packed {
            self.packs().len()
        } else {
            self.primitives().len()
        };
        if !packed && self.primitive_ids().len() != items {
            return err(
                None,
                format!("{items} primitives but {} ids", self.primitive_ids().len()),
            );
        }
        // PERF: one pass in node order, then the leaves' contents and the ids on the builders'
        // threads, the ids as one bit per input index. Validating the 10M-triangle terrain's
        // tree took 0.43 s of its 1.16 s load as a walk from the root with its own stack that
        // checked every leaf on the way and sorted the ids; this way, 0.16 s of 0.47 s (`cargo
        // bench -p rt-benches --bench saved`, two threads).
        //
        // Children come after their parents, so one pass in order sees every parent first: it
        // records each node's parent lane (a node named by two lanes is reached twice, one
        // named by none is unreachable) and depth, and checks each node's boxes inside the box
        // its parent stores for it.
        let n = nodes.len();
        let mut parent = vec![u32::MAX; n];
        let mut depth = vec![0u8; n];
        let mut covered = vec![false; items];
        let (mut leaves, mut deepest) = (0usize, 0usize);
        for (i, node) in nodes.iter().enumerate() {
            let parent_box = match parent[i] {
                _ if i == 0 => None,
                u32::MAX => return err(Some(i), "unreachable from the root".into()),
                p => Some(nodes[p as usize / WIDTH].child_bounds(p as usize % WIDTH)),
            };
            let d = usize::from(depth[i]);
            if d >= MAX_DEPTH {
                return err(
                    Some(i),
                    format!("depth {d} exceeds the traversal stack ({MAX_DEPTH})"),
                );
            }
            let used = node
                .children
                .iter()
                .take_while(|&&c| c != ChildRef::EMPTY.0)
                .count();
            if used == 0 {
                return err(Some(i), "a node without children".into());
            }
            for lane in 0..WIDTH {
                let b = node.child_bounds(lane);
                if lane >= used {
                    if node.children[lane] != ChildRef::EMPTY.0
                        || b != Aabb::new(Vec3::INFINITY, Vec3::NEG_INFINITY)
                    {
                        return err(Some(i), format!("unused lane {lane} is not empty"));
                    }
                    continue;
                }
                if b.is_empty() {
                    return err(Some(i), format!("lane {lane} has an empty box"));
                }
                if let Some(p) = parent_box
                    && !p.contains(&b)
                {
                    return err(
                        Some(i),
                        format!("lane {lane}'s box is not inside its parent's"),
                    );
                }
                let c = node.child(lane);
                if !c.is_leaf() {
                    let k = c.index();
                    if k <= i || k >= n {
                        return err(Some(i), format!("child node {k} out of order"));
                    }
                    if parent[k] != u32::MAX {
                        return err(Some(k), "reached twice".into());
                    }
                    parent[k] = (i * WIDTH + lane) as u32;
                    depth[k] = depth[i] + 1;
                    continue;
                }
                // A leaf is a lane of its node, one level below it.
                leaves += 1;
                deepest = deepest.max(d + 1);
                let range = c.items();
                if range.end > items {
                    return err(Some(i), format!("leaf {range:?} past {items} items"));
                }
                for k in range {
                    if std::mem::replace(&mut covered[k], true) {
                        return err(Some(i), format!("item {k} is in two leaves"));
                    }
                }
            }
        }
        if let Some(k) = covered.iter().position(|c| !c) {
            return err(None, format!("item {k} is in no leaf"));
        }
        self.check_counts(leaves, deepest)?;
        // Every leaf's items inside its box, and the ids, one bit per input index.
        let len = self.input.len;
        let seen: Vec<AtomicU64> = (0..len.div_ceil(64)).map(|_| AtomicU64::new(0)).collect();
        let chunks = rt_core::par::map_chunks(nodes, 1024, |chunk| {
            let mut stored = 0usize;
            for node in chunk {
                for lane in 0..WIDTH {
                    let c = node.child(lane);
                    if c.0 == ChildRef::EMPTY.0 || !c.is_leaf() {
                        continue;
                    }
                    if let Some(m) = self.leaf_fault(c.items(), &node.child_bounds(lane)) {
                        return Err(m);
                    }
                    for k in c.items() {
                        stored += self.mark_ids(k, &seen, len)?;
                    }
                }
            }
            Ok(stored)
        });
        let mut stored = 0;
        for chunk in chunks {
            stored += chunk.map_err(ValidationError::new)?;
        }
        if stored != self.stored || self.stored > self.valid {
            return err(
                None,
                format!(
                    "{stored} ids for {} stored of {} valid primitives",
                    self.stored, self.valid
                ),
            );
        }
        Ok(seen.into_iter().map(AtomicU64::into_inner).collect())
    }

    /// Marks the ids of wide item `k` (a pack's lanes, or one primitive) in `seen`, one bit per
    /// input index below `len`, and returns how many it marked.
    fn mark_ids(&self, k: usize, seen: &[AtomicU64], len: usize) -> Result<usize, String> {
        let one = |id: u32| -> Result<usize, String> {
            let (word, bit) = (id as usize / 64, 1u64 << (id % 64));
            match seen.get(word) {
                Some(w) if (id as usize) < len => {
                    if w.fetch_or(bit, Ordering::Relaxed) & bit != 0 {
                        Err("a primitive id appears twice".into())
                    } else {
                        Ok(1)
                    }
                }
                _ => Err(format!("primitive id {id} is not below the input's {len}")),
            }
        };
        if self.pack_test().is_some() {
            let ids = self.packs()[k].ids;
            ids.iter()
                .filter(|&&id| id != u32::MAX)
                .map(|&id| one(id))
                .sum()
        } else {
            one(self.primitive_ids()[k])
        }
    }
}

/// Whether the first `n` triangles of a pack lie inside `b`, by the same test as
/// `b.contains(&triangle.bounds())` for each, four lanes at a time. Möller–Trumbore packs store
/// edges, so their second and third vertices are rebuilt as `v0 + e`, within a rounding of the
/// input: their boxes are narrowed by that much before the test.
fn pack_inside(pack: &TriPack, n: usize, test: TriangleTest, b: &Aabb) -> bool {
    let (lo_b, hi_b) = (b.min.to_array(), b.max.to_array());
    (0..3).all(|a| {
        let v0 = pack.rows[a];
        let (mut v1, mut v2) = (pack.rows[3 + a], pack.rows[6 + a]);
        if test == TriangleTest::MollerTrumbore {
            for l in 0..PACK {
                v1[l] += v0[l];
                v2[l] += v0[l];
            }
        }
        (0..n).all(|l| {
            let (mut lo, mut hi) = (v0[l].min(v1[l]).min(v2[l]), v0[l].max(v1[l]).max(v2[l]));
            if test == TriangleTest::MollerTrumbore {
                let slack = lo.abs().max(hi.abs()) * (4.0 * f32::EPSILON);
                (lo, hi) = (lo + slack, hi - slack);
            }
            lo >= lo_b[a] && hi <= hi_b[a]
        })
    })
}

/// Checks that the ids are distinct input indices (below `len`) and as many as the tree says
/// it stores, no more than the valid primitives.
fn distinct_ids(
    ids: impl Iterator<Item = u32>,
    len: usize,
    stored: usize,
    valid: usize,
) -> Result<Vec<u64>, ValidationError> {
    let err = |message: String| Err(ValidationError::new(message));
    // One bit per input index rather than sorting the ids: see the PERF note in
    // `validate_wide`.
    let mut seen = vec![0u64; len.div_ceil(64)];
    let mut count = 0usize;
    for id in ids {
        let (word, bit) = (id as usize / 64, 1u64 << (id % 64));
        match seen.get_mut(word) {
            Some(w) if (id as usize) < len => {
                if *w & bit != 0 {
                    return err("a primitive id appears twice".into());
                }
                *w |= bit;
            }
            _ => return err(format!("primitive id {id} is not below the input's {len}")),
        }
        count += 1;
    }
    if count != stored || stored > valid {
        return err(format!(
            "{count} ids for {stored} stored of {valid} valid primitives"
        ));
    }
    Ok(seen)
}

#[cfg(test)]
mod tests {
    use crate::{Bvh, BvhParams, Node, Tree};
    use rt_core::{Accel, Triangle};
    use rt_scene::scenes;

    fn tree() -> Bvh<Triangle> {
        Bvh::build(&scenes::random_soup(500, 1).triangles(), &BvhParams::sah())
    }

    /// A binary tree's nodes and primitive ids, to break on purpose.
    fn parts(b: &mut Bvh<Triangle>) -> (&mut Vec<Node>, &mut Vec<u32>) {
        match &mut b.tree {
            Tree::Binary { nodes, items } => (nodes, &mut items.ids),
            Tree::Wide(_) => panic!("a binary tree"),
        }
    }

    /// `validate` accepts a built tree and rejects each kind of corruption it claims to detect.
    #[test]
    fn detects_each_broken_invariant() {
        assert_eq!(tree().validate(), Ok(()));

        let first_leaf = |b: &Bvh<Triangle>| b.nodes().iter().position(|n| n.is_leaf()).unwrap();
        let first_interior =
            |b: &Bvh<Triangle>| b.nodes().iter().position(|n| !n.is_leaf()).unwrap();

        let mut b = tree();
        let i = first_interior(&b);
        parts(&mut b).0[i].bounds.max.x -= 0.5;
        assert!(
            b.validate()
                .unwrap_err()
                .message
                .contains("not inside its parent")
        );

        let mut b = tree();
        let i = first_leaf(&b);
        parts(&mut b).0[i].bounds.min.y += 0.5;
        assert!(b.validate().is_err());

        let mut b = tree();
        let i = first_leaf(&b);
        parts(&mut b).0[i].index += 1; // overlaps the next leaf's first slot and drops its own
        assert!(b.validate().is_err());

        let mut b = tree();
        parts(&mut b).0[0].index = 0; // second child pointing backwards
        assert!(
            b.validate()
                .unwrap_err()
                .message
                .contains("out of order or range")
        );

        let mut b = tree();
        let ids = parts(&mut b).1;
        ids[3] = ids[4];
        assert!(b.validate().unwrap_err().message.contains("appears twice"));

        let mut b = tree();
        parts(&mut b).1.pop();
        assert!(b.validate().is_err());
    }
}
