//! Per-pixel cost heatmaps: how many nodes (or cells) each primary ray entered, or how many
//! primitives it tested, drawn for several structures side by side on one colour scale (pbrt's
//! `--pixelstats` idea), with a legend that shows the numbers.

use crate::image::per_pixel;
use crate::{Image, ImageError, RenderScene};
use rt_core::Counters;
use rt_core::{DynAccel, Shape};

/// What a heatmap counts per primary ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Nodes or cells entered ([`rt_core::Stats::node_visit`]).
    Visits,
    /// Primitive intersection tests ([`rt_core::Stats::prim_test`]).
    Tests,
}

impl Metric {
    /// `visits` or `tests`.
    pub fn name(self) -> &'static str {
        match self {
            Metric::Visits => "visits",
            Metric::Tests => "tests",
        }
    }

    fn of(self, c: &Counters) -> u32 {
        let n = match self {
            Metric::Visits => c.node_visits,
            Metric::Tests => c.prim_tests,
        };
        n.min(u32::MAX as u64) as u32
    }
}

/// One structure's cost for the primary ray of every pixel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CostMap {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The cost of each pixel's primary ray, row by row from the top left.
    pub values: Vec<u32>,
}

impl CostMap {
    /// The mean cost per ray.
    pub fn mean(&self) -> f64 {
        self.values.iter().map(|&v| v as f64).sum::<f64>() / self.values.len().max(1) as f64
    }

    /// The largest cost.
    pub fn max(&self) -> u32 {
        self.values.iter().copied().max().unwrap_or(0)
    }
}

/// The cost of the primary ray through each pixel centre of `scene`'s camera, traced by
/// `tracer` (built over [`RenderScene::shapes`]), tiles in parallel; `progress` as in
/// [`render`](crate::render).
///
/// # Errors
/// [`ImageError::BadSize`] for an unusable size.
pub fn cost_map(
    scene: &RenderScene,
    tracer: &dyn DynAccel<Shape>,
    width: u32,
    height: u32,
    metric: Metric,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CostMap, ImageError> {
    let raster = scene.camera.raster(width, height);
    let values = per_pixel(width, height, progress, |x, y| {
        let mut counters = Counters::default();
        tracer.intersect_dyn(
            &raster.ray(x as f32 + 0.5, y as f32 + 0.5),
            Some(&mut counters),
        );
        metric.of(&counters)
    })?;
    Ok(CostMap {
        width,
        height,
        values,
    })
}

/// Viridis (van der Walt & Smith, matplotlib's default map) at eleven evenly spaced points:
/// perceptually uniform, readable in grey and by colour-blind viewers.
const VIRIDIS: [[u8; 3]; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

/// The colour of `t` in `[0, 1]` on the viridis map.
pub fn viridis(t: f32) -> [u8; 3] {
    let x = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * 10.0;
    let i = (x as usize).min(9);
    let f = x - i as f32;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    [0, 1, 2].map(|k| (a[k] as f32 + (b[k] as f32 - a[k] as f32) * f + 0.5) as u8)
}

/// The colour scale shared by every panel: from 0 to `max`, logarithmic when the costs span a
/// wide range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// The cost at the top of the scale (the largest of all panels).
    pub max: u32,
    /// Whether the scale is `ln(1 + cost)` rather than the cost.
    pub log: bool,
}

impl Scale {
    /// The scale for these panels: linear up to the largest cost, unless that exceeds 8 times
    /// the median cost of all pixels, where a linear scale would paint most of the picture in
    /// the bottom eighth of the colours; then logarithmic.
    pub fn of(panels: &[(String, CostMap)]) -> Self {
        let max = panels.iter().map(|(_, c)| c.max()).max().unwrap_or(0);
        let mut all: Vec<u32> = panels
            .iter()
            .flat_map(|(_, c)| c.values.iter().copied())
            .collect();
        let median = if all.is_empty() {
            0
        } else {
            let mid = all.len() / 2;
            *all.select_nth_unstable(mid).1
        };
        Self {
            max,
            log: max as u64 > 8 * median.max(1) as u64,
        }
    }

    /// Where `cost` sits on the scale, in `[0, 1]`.
    pub fn position(&self, cost: f64) -> f32 {
        if self.max == 0 {
            return 0.0;
        }
        let t = if self.log {
            (1.0 + cost).ln() / (1.0 + self.max as f64).ln()
        } else {
            cost / self.max as f64
        };
        t.clamp(0.0, 1.0) as f32
    }

    /// The costs to label on the legend: 0, then powers of ten (log) or quarters (linear), and
    /// the maximum.
    pub fn ticks(&self) -> Vec<u32> {
        let mut ticks = vec![0];
        if self.log {
            let mut p = 1u64;
            while p < self.max as u64 {
                ticks.push(p as u32);
                p *= 10;
            }
        } else {
            for q in 1..4 {
                ticks.push((self.max as u64 * q / 4) as u32);
            }
        }
        ticks.push(self.max);
        ticks.dedup();
        ticks
    }
}

const GAP: u32 = 8;
const TEXT: u32 = 8;
const LABEL_BAR: u32 = 2 * TEXT + 8;
const LEGEND_BAR: u32 = 14;
const LEGEND: u32 = 6 + LEGEND_BAR + 6 + 2 * TEXT + 6 + 2 * TEXT + 4;
const BACKGROUND: [u8; 3] = [24, 24, 28];
const INK: [u8; 3] = [235, 235, 235];

/// Writes `text` (ASCII; anything else shows as `?`) with its top left at `(x, y)`, each font
/// pixel `scale` pixels wide; what falls outside the image is clipped.
pub fn draw_text(image: &mut Image, x: u32, y: u32, text: &str, scale: u32, color: [u8; 3]) {
    for (i, ch) in text.chars().enumerate() {
        let code = if ch.is_ascii() {
            ch as usize
        } else {
            b'?' as usize
        };
        let glyph = font8x8::legacy::BASIC_LEGACY[code];
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8u32 {
                if bits >> col & 1 == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let px = x + (i as u32 * 8 + col) * scale + dx;
                        let py = y + row as u32 * scale + dy;
                        if px < image.width && py < image.height {
                            image.pixels[(py * image.width + px) as usize] = color;
                        }
                    }
                }
            }
        }
    }
}

/// Width in pixels of `text` drawn at `scale`.
pub fn text_width(text: &str, scale: u32) -> u32 {
    text.chars().count() as u32 * 8 * scale
}

/// The panels side by side on one [`Scale`], each under a label with the structure's name and
/// mean cost, above a legend: the colour bar with the costs it stands for.
pub fn heatmap_strip(panels: &[(String, CostMap)], metric: Metric) -> Image {
    let scale = Scale::of(panels);
    let (w, h) = panels.first().map_or((1, 1), |(_, c)| (c.width, c.height));
    let n = panels.len().max(1) as u32;
    let width = n * w + (n + 1) * GAP;
    let height = LABEL_BAR + h + LEGEND + GAP;
    let mut image = Image {
        width,
        height,
        pixels: vec![BACKGROUND; (width * height) as usize],
    };
    let text_scale = if w >= 240 { 2 } else { 1 };
    for (k, (name, costs)) in panels.iter().enumerate() {
        let x0 = GAP + k as u32 * (w + GAP);
        let label = format!("{name}: mean {:.1}", costs.mean());
        draw_text(&mut image, x0, 4, &label, text_scale, INK);
        for y in 0..h.min(costs.height) {
            for x in 0..w.min(costs.width) {
                let v = costs.values[(y * costs.width + x) as usize];
                image.pixels[((LABEL_BAR + y) * width + x0 + x) as usize] =
                    viridis(scale.position(v as f64));
            }
        }
    }
    // The legend: a colour bar across the strip, tick marks and numbers under it.
    let (bar_x, bar_w) = (GAP, width - 2 * GAP);
    let bar_y = LABEL_BAR + h + 6;
    let position_at = |x: u32| (x - bar_x) as f32 / (bar_w - 1).max(1) as f32;
    for x in bar_x..bar_x + bar_w {
        // Invert the scale: the bar shows colours evenly, each standing for its cost.
        let c = viridis(position_at(x));
        for y in bar_y..bar_y + LEGEND_BAR {
            image.pixels[(y * width + x) as usize] = c;
        }
    }
    let text_y = bar_y + LEGEND_BAR + 6;
    let mut last_end = 0u32;
    for tick in scale.ticks() {
        let x = bar_x + (scale.position(tick as f64) * (bar_w - 1) as f32).round() as u32;
        for y in bar_y + LEGEND_BAR..bar_y + LEGEND_BAR + 4 {
            image.pixels[(y * width + x) as usize] = INK;
        }
        let label = tick.to_string();
        let tw = text_width(&label, text_scale);
        let lx = x
            .saturating_sub(tw / 2)
            .clamp(bar_x, bar_x + bar_w - tw.min(bar_w));
        // Skip a label that would overlap the previous one (the maximum is always drawn last
        // and wins over a crowded power of ten).
        if lx < last_end + 4 && tick != scale.max {
            continue;
        }
        draw_text(&mut image, lx, text_y, &label, text_scale, INK);
        last_end = lx + tw;
    }
    let caption = format!(
        "{} per primary ray, {} scale",
        metric.name(),
        if scale.log { "log" } else { "linear" }
    );
    let cw = text_width(&caption, text_scale);
    let cx = (width.saturating_sub(cw)) / 2;
    let caption_y = text_y + TEXT * text_scale + 6;
    draw_text(
        &mut image,
        cx,
        caption_y,
        &caption,
        text_scale,
        [170, 170, 170],
    );
    image
}

/// The mean colour of a panel region, for tests: linear RGB in `[0, 1]`.
#[cfg(test)]
fn mean_color(pixels: &[[u8; 3]]) -> rt_core::glam::Vec3 {
    use rt_core::glam::Vec3;
    pixels
        .iter()
        .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / 255.0)
        .sum::<Vec3>()
        / pixels.len().max(1) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(values: Vec<u32>) -> CostMap {
        CostMap {
            width: values.len() as u32,
            height: 1,
            values,
        }
    }

    #[test]
    fn scale_is_linear_for_narrow_ranges_and_log_for_wide_ones() {
        let narrow = Scale::of(&[("a".into(), map(vec![10, 20, 30, 40]))]);
        assert!(!narrow.log);
        assert_eq!(narrow.ticks(), vec![0, 10, 20, 30, 40]);
        let wide = Scale::of(&[
            ("a".into(), map(vec![3, 4, 5, 6])),
            ("b".into(), map(vec![5, 6, 7, 2000])),
        ]);
        assert!(wide.log);
        assert_eq!(wide.ticks(), vec![0, 1, 10, 100, 1000, 2000]);
        assert_eq!(wide.position(2000.0), 1.0);
        assert!(wide.position(100.0) > 0.5);
    }

    #[test]
    fn strip_shows_panels_on_one_scale() {
        let cheap = map(vec![1; 300]);
        let dear = map(vec![9; 300]);
        let strip = heatmap_strip(
            &[("cheap".into(), cheap), ("dear".into(), dear)],
            Metric::Tests,
        );
        assert_eq!(strip.width, 2 * 300 + 3 * GAP);
        let row = |x0: u32| {
            let y = LABEL_BAR;
            let start = (y * strip.width + x0) as usize;
            mean_color(&strip.pixels[start..start + 300])
        };
        let (a, b) = (row(GAP), row(2 * GAP + 300));
        // Viridis runs from dark purple to bright yellow: the dearer panel is brighter.
        assert!(b.length() > a.length() + 0.5, "{a} {b}");
        // The label bar carries text (some ink pixels).
        let label: Vec<[u8; 3]> = strip.pixels[..(LABEL_BAR * strip.width) as usize].to_vec();
        assert!(label.contains(&INK));
    }

    #[test]
    fn viridis_ends() {
        assert_eq!(viridis(0.0), VIRIDIS[0]);
        assert_eq!(viridis(1.0), VIRIDIS[10]);
        assert_eq!(viridis(f32::NAN), VIRIDIS[0]);
    }
}
