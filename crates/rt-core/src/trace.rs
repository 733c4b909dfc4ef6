//! One ray's walk, step by step: the events a traversal reports to a sink whose
//! [`Stats::TRACE`] is true, and [`Trace`], the sink that records them and prints the walk.
//!
//! Traversals report every event inside `if S::TRACE { ... }`. The flag is an associated
//! constant, so for [`NoStats`](crate::NoStats) and [`Counters`] the branch, and whatever it
//! computes only for the trace (a node's interval, the outcome of a test), is removed at
//! compile time; `cargo bench -p rt-benches --bench stats` checks that the uncounted walk still
//! runs as fast as one written with no sink.
//!
//! ```
//! use rt_core::{Accel, BruteForce, Ray, Trace, Triangle, glam::Vec3};
//! let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
//! let accel = BruteForce::build(&tris, &Default::default());
//! let mut trace = Trace::default();
//! accel.intersect_with(&Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z), &mut trace);
//! assert_eq!(trace.to_string(), "test primitive 0: hit at t = 1\n");
//! ```

pub use crate::event::{Event, Outcome, Place, Take};
use crate::{Counters, Stats};
use std::fmt;

/// The sink that records every event of the walks it is given, with their counts. Its
/// `Display` prints the walk, one line per event, with the events inside a node indented under
/// the line that entered it.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    /// The events, in the order the traversal reported them.
    pub events: Vec<Event>,
    /// The counts, as [`Counters`] would keep them.
    pub counters: Counters,
}

impl Stats for Trace {
    const TRACE: bool = true;

    fn node_visit(&mut self) {
        self.counters.node_visit();
    }
    fn prim_test(&mut self) {
        self.counters.prim_test();
    }
    fn mailbox_skip(&mut self) {
        self.counters.mailbox_skip();
    }
    fn add(&mut self, counters: &Counters) {
        self.counters.add(counters);
    }
    fn event(&mut self, event: Event) {
        self.events.push(event);
    }
}

/// Reports the event `make` builds, if the sink traces: the way traversals call
/// [`Stats::event`], so that the event is not even built for a sink that does not trace.
#[inline(always)]
pub fn report<S: Stats>(stats: &mut S, make: impl FnOnce() -> Event) {
    if S::TRACE {
        stats.event(make());
    }
}

/// Reports the test of primitive `prim` with what it found (`hit`: a closest-hit test's `t`,
/// if any).
#[inline(always)]
pub fn tested<S: Stats>(stats: &mut S, prim: u32, hit: Option<f32>) {
    report(stats, || Event::Test {
        prim,
        outcome: hit.map_or(Outcome::Miss, Outcome::Hit),
    });
}

/// Reports the any-hit test of primitive `prim` with its answer.
#[inline(always)]
pub fn blocked<S: Stats>(stats: &mut S, prim: u32, blocks: bool) {
    report(stats, || Event::Test {
        prim,
        outcome: if blocks {
            Outcome::Blocks
        } else {
            Outcome::Miss
        },
    });
}

impl fmt::Display for Trace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut entered = false;
        for e in &self.events {
            if matches!(e, Event::Enter { .. } | Event::Pop { .. }) {
                entered = matches!(e, Event::Enter { .. });
                writeln!(f, "{e}")?;
            } else if entered {
                writeln!(f, "  {e}")?;
            } else {
                writeln!(f, "{e}")?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_under_an_entered_node_are_indented() {
        let trace = Trace {
            events: vec![
                Event::Enter {
                    place: Place::Leaf(3),
                    t0: 1.0,
                    t1: 2.5,
                    bounds: None,
                },
                Event::Test {
                    prim: 7,
                    outcome: Outcome::Miss,
                },
                Event::Pop {
                    place: Place::Node(9),
                    t: 4.0,
                    skipped: true,
                },
            ],
            counters: Counters::default(),
        };
        assert_eq!(
            trace.to_string(),
            "enter leaf 3, t in [1, 2.5]\n  test primitive 7: miss\n\
             pop node 9: skipped, it starts at t = 4, beyond the best hit\n"
        );
    }
}
