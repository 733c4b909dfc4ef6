//! The steps of a walk, as a traversal reports them to a sink whose
//! [`Stats::TRACE`](crate::Stats::TRACE) is true: what [`Trace`](crate::Trace) records and
//! prints. They live apart from the sink so that [`Stats`](crate::Stats) can name them.

use crate::Aabb;
use std::fmt;

/// A node, leaf or cell a traversal enters, named the way its structure numbers them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Place {
    /// An interior node (or a node not yet known to be a leaf), by its index.
    Node(u32),
    /// A leaf, by its index (for the wide BVH, the index of its first item).
    Leaf(u32),
    /// A grid cell by its integer coordinates; `grid` is 0 for a uniform grid and for the top
    /// grid of a hierarchical one, and the nested grid's number otherwise.
    Cell {
        /// Which grid (0: the top or only grid).
        grid: u32,
        /// The cell's coordinates along x, y and z.
        cell: [u32; 3],
    },
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::Node(i) => write!(f, "node {i}"),
            Place::Leaf(i) => write!(f, "leaf {i}"),
            Place::Cell { grid: 0, cell } => write!(f, "cell {cell:?}"),
            Place::Cell { grid, cell } => write!(f, "cell {cell:?} of nested grid {grid}"),
        }
    }
}

/// Which children of a split plane a ray goes on to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Take {
    /// Only the child on the origin's side: the plane is crossed outside the interval.
    Near,
    /// Only the far child: the plane is crossed before the interval starts.
    Far,
    /// The near child first, then the far one (pushed).
    Both,
    /// The ray lies in the plane: both children over the whole interval.
    InPlane,
}

/// What one primitive test found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// No hit in the interval still open (up to the best hit so far).
    Miss,
    /// A hit at this `t`, closer than the best so far when it was tested.
    Hit(f32),
    /// An any-hit query found that the primitive blocks the ray (its `t` is not computed).
    Blocks,
}

/// One step of a traversal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A node, leaf or cell was entered; the ray's interval in it is `[t0, t1]` as far as the
    /// traversal knows it (`t1` is infinite where the walk does not compute an exit).
    Enter {
        /// What was entered.
        place: Place,
        /// Where the ray enters it.
        t0: f32,
        /// Where the ray leaves it.
        t1: f32,
        /// The region it covers, where the traversal has it at hand.
        bounds: Option<Aabb>,
    },
    /// A child's box that the ray enters at `t` (children it misses are not reported).
    Child {
        /// The child.
        place: Place,
        /// Where the ray enters its box.
        t: f32,
    },
    /// A split plane at `pos` on `axis`, crossed at `t`, and where the ray goes.
    Split {
        /// 0, 1 or 2 for x, y, z.
        axis: usize,
        /// The plane's coordinate.
        pos: f32,
        /// Where the ray crosses it (NaN when the ray lies in it).
        t: f32,
        /// The child on the origin's side.
        near: Place,
        /// The other child.
        far: Place,
        /// Which of them the ray goes on to.
        take: Take,
    },
    /// A subtree deferred to the stack; the ray enters it no sooner than `t`.
    Push {
        /// The subtree.
        place: Place,
        /// Its entry distance.
        t: f32,
    },
    /// A subtree taken from the stack: entered, or skipped because it starts beyond the best
    /// hit so far.
    Pop {
        /// The subtree.
        place: Place,
        /// Its entry distance.
        t: f32,
        /// Whether it was skipped.
        skipped: bool,
    },
    /// A primitive was tested.
    Test {
        /// Its index in the build input.
        prim: u32,
        /// What the test found.
        outcome: Outcome,
    },
    /// A primitive was not tested again: the mailbox showed this ray had tested it.
    Skip {
        /// Its index in the build input.
        prim: u32,
    },
    /// A decision in words (why a walk stops, restarts, descends into a nested grid, ...).
    Note(&'static str),
}

/// A distance printed with at most six significant digits, trailing zeros dropped.
pub(crate) fn short(t: f32) -> String {
    if !t.is_finite() {
        return if t.is_nan() {
            "NaN".into()
        } else if t > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        };
    }
    let v: f64 = format!("{t:.5e}").parse().unwrap_or(t as f64);
    let plain = format!("{v}");
    if plain.len() > 12 {
        format!("{v:e}")
    } else {
        plain
    }
}

impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let axis = |a: usize| ["x", "y", "z"].get(a).copied().unwrap_or("?");
        match *self {
            Event::Enter {
                place,
                t0,
                t1,
                bounds,
            } => {
                write!(f, "enter {place}, t in [{}, {}]", short(t0), short(t1))?;
                if let Some(b) = bounds {
                    write!(
                        f,
                        ", box ({}, {}, {})..({}, {}, {})",
                        short(b.min.x),
                        short(b.min.y),
                        short(b.min.z),
                        short(b.max.x),
                        short(b.max.y),
                        short(b.max.z)
                    )?;
                }
                Ok(())
            }
            Event::Child { place, t } => write!(f, "child {place}: entered at t = {}", short(t)),
            Event::Split {
                axis: a,
                pos,
                t,
                near,
                far,
                take,
            } => {
                write!(
                    f,
                    "split {} = {}, crossed at t = {}: near {near}, far {far}; ",
                    axis(a),
                    short(pos),
                    short(t)
                )?;
                f.write_str(match take {
                    Take::Near => "near side only",
                    Take::Far => "far side only",
                    Take::Both => "near first, far pushed",
                    Take::InPlane => "ray in the plane: both sides",
                })
            }
            Event::Push { place, t } => write!(f, "push {place} (entered at t = {})", short(t)),
            Event::Pop {
                place,
                t,
                skipped: false,
            } => write!(f, "pop {place} (t = {})", short(t)),
            Event::Pop {
                place,
                t,
                skipped: true,
            } => write!(
                f,
                "pop {place}: skipped, it starts at t = {}, beyond the best hit",
                short(t)
            ),
            Event::Test { prim, outcome } => match outcome {
                Outcome::Miss => write!(f, "test primitive {prim}: miss"),
                Outcome::Hit(t) => write!(f, "test primitive {prim}: hit at t = {}", short(t)),
                Outcome::Blocks => write!(f, "test primitive {prim}: blocks the ray"),
            },
            Event::Skip { prim } => {
                write!(f, "skip primitive {prim}: already tested (mailbox)")
            }
            Event::Note(s) => f.write_str(s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_print_short() {
        assert_eq!(short(1.0), "1");
        assert_eq!(short(0.1), "0.1");
        assert_eq!(short(1.0 / 3.0), "0.333333");
        assert_eq!(short(f32::INFINITY), "inf");
        assert_eq!(short(1e30), "1e30");
    }
}
