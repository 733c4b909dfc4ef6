//! Drawings of a structure: a slice through its nodes or cells at an axis-aligned plane, with
//! the mesh's cross-section, as SVG. These are the lectures' figures of split planes, boxes and
//! cells, drawn from a real build.

use crate::heatmap::viridis;
use rt_core::glam::{Vec2, Vec3};
use rt_core::{Aabb, Region, Triangle};
use std::collections::BTreeMap;
use svg::Document;
use svg::node::element::path::Data;
use svg::node::element::{Group, Path, Rectangle, Text};

/// What the fill colour of a leaf or cell shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coloring {
    /// Its depth in the structure.
    Depth,
    /// How many primitive references it lists (on a logarithmic scale).
    Prims,
}

/// Where to cut and how to draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceOptions {
    /// The axis the plane is perpendicular to (0 = x, 1 = y, 2 = z).
    pub axis: usize,
    /// Where the plane lies along that axis, as a fraction of the scene box (0 to 1).
    pub at: f32,
    /// What fills the leaves and cells.
    pub coloring: Coloring,
    /// Width of the drawing area in SVG units (pixels).
    pub width: f32,
}

/// How many regions of each kind a slice drew, and where it cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceSummary {
    /// The plane's coordinate.
    pub plane: f32,
    /// Leaves and cells drawn (filled).
    pub leaves: usize,
    /// Interior nodes drawn (outlined, or as split lines).
    pub interior: usize,
    /// Segments of the mesh's cross-section.
    pub segments: usize,
}

/// The two axes the drawing shows for a plane perpendicular to `axis`: horizontal, then
/// vertical (drawn upwards). `y` is up whenever it is shown.
pub fn view_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (2, 1),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// Where triangle `t` meets the plane `x[axis] = c`: a segment, or `None`. A triangle lying in
/// the plane is drawn by its edges elsewhere, not here.
pub fn cross_section(t: &Triangle, axis: usize, c: f32) -> Option<(Vec3, Vec3)> {
    let v = [t.v0, t.v1, t.v2];
    let d = v.map(|p| p[axis] - c);
    let mut points = Vec::with_capacity(3);
    for k in 0..3 {
        let (a, b) = (k, (k + 1) % 3);
        if d[a] == 0.0 {
            points.push(v[a]);
        }
        if (d[a] < 0.0 && d[b] > 0.0) || (d[a] > 0.0 && d[b] < 0.0) {
            let s = d[a] / (d[a] - d[b]);
            points.push(v[a] + (v[b] - v[a]) * s);
        }
    }
    points.dedup();
    match points[..] {
        [p, q] | [p, q, _] if p != q => Some((p, q)),
        _ => None,
    }
}

/// A drawing coordinate to a tenth of a unit: finer than any screen shows, and short in the file.
fn round(v: f32) -> f32 {
    (v * 10.0).round() / 10.0
}

/// Draws `regions` (from [`rt_core::Accel::regions`]) and the cross-section of `triangles` where
/// they meet a plane across `bounds` (the scene's box), with a title and a colour legend.
pub fn slice_svg(
    title: &str,
    triangles: &[Triangle],
    regions: &[Region],
    bounds: &Aabb,
    options: &SliceOptions,
) -> (Document, SliceSummary) {
    let axis = options.axis.min(2);
    let plane =
        bounds.min[axis] + options.at.clamp(0.0, 1.0) * (bounds.max[axis] - bounds.min[axis]);
    let (ua, va) = view_axes(axis);
    let lo = Vec2::new(bounds.min[ua], bounds.min[va]);
    let extent = Vec2::new(bounds.max[ua], bounds.max[va]) - lo;
    let margin = 20.0;
    let width = options.width.max(100.0);
    let scale = (width - 2.0 * margin) / extent.x.max(extent.y * 1e-3).max(f32::MIN_POSITIVE);
    let draw_h = (extent.y * scale).max(1.0);
    let top = 40.0;
    let legend_h = 76.0;
    let height = top + draw_h + legend_h;
    let to_svg = |p: Vec3| -> (f32, f32) {
        (
            margin + (p[ua] - lo.x) * scale,
            top + draw_h - (p[va] - lo.y) * scale,
        )
    };

    let hit: Vec<&Region> = regions
        .iter()
        .filter(|r| r.bounds.min[axis] <= plane && plane <= r.bounds.max[axis])
        .collect();
    let max_depth = hit.iter().map(|r| r.depth).max().unwrap_or(0);
    let max_prims = hit.iter().filter_map(|r| r.prims).max().unwrap_or(0);
    let position = |r: &Region| -> f32 {
        match options.coloring {
            Coloring::Depth => r.depth as f32 / max_depth.max(1) as f32,
            Coloring::Prims => {
                let n = r.prims.unwrap_or(0) as f32;
                (1.0 + n).ln() / (1.0 + max_prims as f32).ln().max(f32::MIN_POSITIVE)
            }
        }
    };
    let hex = |c: [u8; 3]| format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2]);

    // Shapes of one colour share one path: a drawing of thousands of cells stays small.
    let mut fills: BTreeMap<String, Data> = BTreeMap::new();
    let mut strokes: BTreeMap<String, Data> = BTreeMap::new();
    let mut summary = SliceSummary {
        plane,
        leaves: 0,
        interior: 0,
        segments: 0,
    };
    let depth_color = |r: &Region| hex(viridis(r.depth as f32 / max_depth.max(1) as f32));
    for r in &hit {
        let (x0, y1) = to_svg(r.bounds.min);
        let (x1, y0) = to_svg(r.bounds.max);
        let (x0, y0, x1, y1) = (round(x0), round(y0), round(x1), round(y1));
        let rect = |d: Data| {
            d.move_to((x0, y0))
                .horizontal_line_to(x1)
                .vertical_line_to(y1)
                .horizontal_line_to(x0)
                .close()
        };
        match (r.prims, r.split) {
            (Some(n), _) => {
                let fill = if n == 0 {
                    "#ffffff".to_string()
                } else {
                    hex(viridis(position(r)))
                };
                let d = fills.remove(&fill).unwrap_or_default();
                fills.insert(fill, rect(d));
                summary.leaves += 1;
            }
            (None, Some((split_axis, pos))) if split_axis != axis => {
                // A kd-tree split: the plane's trace across the node's box.
                let ((ax, ay), (bx, by)) = if split_axis == ua {
                    let x = round(to_svg(Vec3::splat(pos)).0);
                    ((x, y0), (x, y1))
                } else {
                    let y = round(to_svg(Vec3::splat(pos)).1);
                    ((x0, y), (x1, y))
                };
                let key = depth_color(r);
                let d = strokes.remove(&key).unwrap_or_default();
                strokes.insert(key, d.move_to((ax, ay)).line_to((bx, by)));
                summary.interior += 1;
            }
            (None, Some(_)) => {}
            (None, None) => {
                let key = depth_color(r);
                let d = strokes.remove(&key).unwrap_or_default();
                strokes.insert(key, rect(d));
                summary.interior += 1;
            }
        }
    }
    let mut leaves = Group::new()
        .set("stroke", "#202020")
        .set("stroke-width", 0.4)
        .set("fill-opacity", 0.55);
    for (fill, d) in fills {
        leaves = leaves.add(Path::new().set("fill", fill).set("d", d));
    }
    let mut interior = Group::new().set("fill", "none").set("stroke-width", 1.0);
    for (stroke, d) in strokes {
        interior = interior.add(Path::new().set("stroke", stroke).set("d", d));
    }

    let mut data = Data::new();
    for t in triangles {
        if let Some((p, q)) = cross_section(t, axis, plane) {
            let (p, q) = (to_svg(p), to_svg(q));
            data = data
                .move_to((round(p.0), round(p.1)))
                .line_to((round(q.0), round(q.1)));
            summary.segments += 1;
        }
    }
    let mesh = Path::new()
        .set("d", data)
        .set("fill", "none")
        .set("stroke", "#d01010")
        .set("stroke-width", 1.2)
        .set("stroke-linecap", "round");

    let axis_name = ["x", "y", "z"];
    let heading = Text::new(format!(
        "{title}: slice {} = {plane:.4} ({:.2} of the box); {} leaves or cells, {} interior nodes",
        axis_name[axis], options.at, summary.leaves, summary.interior
    ))
    .set("x", margin)
    .set("y", 24)
    .set("font-family", "sans-serif")
    .set("font-size", 14);

    // The legend: a colour bar and its end labels, the mesh's colour, the axes shown.
    let legend_y = top + draw_h + 16.0;
    let bar_w = (width - 2.0 * margin) * 0.5;
    let mut legend = Group::new()
        .set("font-family", "sans-serif")
        .set("font-size", 12);
    let steps = 32;
    for k in 0..steps {
        let t = k as f32 / (steps - 1) as f32;
        legend = legend.add(
            Rectangle::new()
                .set("x", margin + bar_w * k as f32 / steps as f32)
                .set("y", legend_y)
                .set("width", bar_w / steps as f32 + 0.5)
                .set("height", 12)
                .set("fill", hex(viridis(t))),
        );
    }
    let (low, high, what) = match options.coloring {
        Coloring::Depth => ("0".to_string(), max_depth.to_string(), "depth"),
        Coloring::Prims => (
            "0".to_string(),
            max_prims.to_string(),
            "primitives per leaf or cell (log scale; white: empty)",
        ),
    };
    legend = legend
        .add(Text::new(low).set("x", margin).set("y", legend_y + 28.0))
        .add(
            Text::new(high)
                .set("x", margin + bar_w)
                .set("y", legend_y + 28.0)
                .set("text-anchor", "end"),
        )
        .add(
            Text::new(format!(
                "{what}; red: the mesh's cross-section; right: {}, up: {}",
                axis_name[ua], axis_name[va]
            ))
            .set("x", margin)
            .set("y", legend_y + 46.0),
        );

    let document = Document::new()
        .set("viewBox", (0.0, 0.0, width, height))
        .set("width", width)
        .set("height", height)
        .add(
            Rectangle::new()
                .set("width", "100%")
                .set("height", "100%")
                .set("fill", "#fafafa"),
        )
        .add(heading)
        .add(leaves)
        .add(interior)
        .add(mesh)
        .add(legend);
    (document, summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_section_of_a_triangle() {
        let t = Triangle::new(
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        );
        let (p, q) = cross_section(&t, 0, 1.0).unwrap();
        let mut ys = [p.y, q.y];
        ys.sort_by(f32::total_cmp);
        assert_eq!((p.x, q.x), (1.0, 1.0));
        assert_eq!(ys, [0.0, 1.0]);
        assert!(cross_section(&t, 0, 3.0).is_none());
        // Through a vertex only: a point, no segment.
        assert!(cross_section(&t, 0, 2.0).is_none());
    }

    #[test]
    fn draws_leaves_splits_and_mesh() {
        let bounds = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let mut left = bounds;
        left.max.x = 0.5;
        let regions = [
            Region {
                bounds,
                depth: 0,
                prims: None,
                split: Some((0, 0.5)),
            },
            Region {
                bounds: left,
                depth: 1,
                prims: Some(3),
                split: None,
            },
        ];
        let tri = Triangle::new(Vec3::ZERO, Vec3::ONE, Vec3::new(1.0, 0.0, 1.0));
        let options = SliceOptions {
            axis: 2,
            at: 0.5,
            coloring: Coloring::Prims,
            width: 400.0,
        };
        let (doc, summary) = slice_svg("test", &[tri], &regions, &bounds, &options);
        assert_eq!(summary.plane, 0.5);
        assert_eq!(
            (summary.leaves, summary.interior, summary.segments),
            (1, 1, 1)
        );
        let text = doc.to_string();
        // The split at x = 0.5 is a vertical line in the middle of the 360-unit-wide area.
        assert!(
            text.contains("M200,") && text.contains("test: slice z"),
            "{text}"
        );
    }
}
