//! Traversal statistics through a generic sink.
//!
//! Traversal code is generic over [`Stats`] and calls it at each node visit and primitive test.
//! With [`NoStats`] every call is an empty `#[inline(always)]` function, so the counting code
//! disappears after monomorphization; `benches/benches/stats.rs` checks that the uncounted path is
//! as fast as a traversal written with no counters at all.

/// Receives traversal events. Implement it to collect your own statistics.
///
/// The three counting calls are made by every traversal. A sink that sets [`Stats::TRACE`]
/// also receives, through [`Stats::event`], each step with its context (the node or cell
/// entered and its interval, split planes and the side taken, pushes and pops, each test's
/// outcome): what [`Trace`](crate::Trace) records to explain one ray.
pub trait Stats {
    /// Whether this sink wants [`Stats::event`] calls. Traversals report events only under
    /// `if S::TRACE`, so a sink that leaves it `false` pays nothing for them.
    const TRACE: bool = false;

    /// Whether this sink records anything. Layers that call structures through trait objects
    /// (the instances of a two-level scene, see [`DynAccel`](crate::DynAccel)) cannot pass a generic
    /// sink down; they take the uncounted path when this is `false` (as for [`NoStats`]) and
    /// otherwise count into [`Counters`] and hand them over with [`Stats::add`].
    const COUNTS: bool = true;

    /// A node (or cell) was entered.
    fn node_visit(&mut self);
    /// A primitive was intersected.
    fn prim_test(&mut self);
    /// A primitive test was skipped because a mailbox showed the primitive was already tested.
    #[inline(always)]
    fn mailbox_skip(&mut self) {}
    /// A bundle of `lanes` rays, `active` of them still tracing there, entered the node or
    /// cell just reported by [`Stats::node_visit`] (see the [`bundle`](crate::bundle) module:
    /// a bundle's step counts as one visit).
    #[inline(always)]
    fn bundle_lanes(&mut self, lanes: u32, active: u32) {
        let _ = (lanes, active);
    }
    /// A bundle traversal gave one of its rays to the single-ray traversal (a ray that cannot
    /// travel in a bundle, or one of too few lanes left active); that ray's events follow as a
    /// single ray's.
    #[inline(always)]
    fn single_ray(&mut self) {}
    /// Counts gathered elsewhere (by a structure called through a trait object), added as if
    /// each event had been reported here.
    fn add(&mut self, counters: &Counters) {
        for _ in 0..counters.node_visits {
            self.node_visit();
        }
        for _ in 0..counters.prim_tests {
            self.prim_test();
        }
        for _ in 0..counters.mailbox_skips {
            self.mailbox_skip();
        }
        for _ in 0..counters.single_rays {
            self.single_ray();
        }
        // The lane counts add up as one step of their totals: what a sink can sum of them.
        if counters.lane_slots != 0 {
            let clamp = |x: u64| x.min(u32::MAX as u64) as u32;
            self.bundle_lanes(clamp(counters.lane_slots), clamp(counters.lanes_active));
        }
    }
    /// One step of the walk, with its context; called only when [`Stats::TRACE`] is true.
    #[inline(always)]
    fn event(&mut self, event: crate::event::Event) {
        let _ = event;
    }
}

/// The sink that records nothing and compiles away.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoStats;

impl Stats for NoStats {
    const COUNTS: bool = false;
    #[inline(always)]
    fn add(&mut self, _: &Counters) {}
    #[inline(always)]
    fn node_visit(&mut self) {}
    #[inline(always)]
    fn prim_test(&mut self) {}
}

/// Plain event counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Nodes or cells entered.
    pub node_visits: u64,
    /// Primitive intersection tests.
    pub prim_tests: u64,
    /// Primitive tests a mailbox saved.
    pub mailbox_skips: u64,
    /// Over the node visits of bundles, the lanes the bundles carried.
    pub lane_slots: u64,
    /// Over the node visits of bundles, the lanes still active there.
    pub lanes_active: u64,
    /// Rays a bundle traversal traced singly.
    pub single_rays: u64,
}

impl Counters {
    /// The sum of two sets of counters (for reducing over threads).
    pub fn merged(self, o: Self) -> Self {
        Self {
            node_visits: self.node_visits + o.node_visits,
            prim_tests: self.prim_tests + o.prim_tests,
            mailbox_skips: self.mailbox_skips + o.mailbox_skips,
            lane_slots: self.lane_slots + o.lane_slots,
            lanes_active: self.lanes_active + o.lanes_active,
            single_rays: self.single_rays + o.single_rays,
        }
    }

    /// The share of a bundle's lanes active at the nodes it visited (1 when every lane walks
    /// every node the bundle does), or `None` when no bundle was counted.
    pub fn lane_utilisation(&self) -> Option<f64> {
        (self.lane_slots != 0).then(|| self.lanes_active as f64 / self.lane_slots as f64)
    }
}

impl Stats for Counters {
    #[inline]
    fn add(&mut self, c: &Counters) {
        *self = self.merged(*c);
    }
    #[inline(always)]
    fn node_visit(&mut self) {
        self.node_visits += 1;
    }
    #[inline(always)]
    fn prim_test(&mut self) {
        self.prim_tests += 1;
    }
    #[inline(always)]
    fn mailbox_skip(&mut self) {
        self.mailbox_skips += 1;
    }
    #[inline(always)]
    fn bundle_lanes(&mut self, lanes: u32, active: u32) {
        self.lane_slots += lanes as u64;
        self.lanes_active += active as u64;
    }
    #[inline(always)]
    fn single_ray(&mut self) {
        self.single_rays += 1;
    }
}
