//! Many rays in one call: what [`Accel::intersect_bundle`] and [`Accel::occluded_bundle`]
//! promise, the loops behind their defaults, and frames in image order on all threads.
//!
//! A bundle query answers a slice of rays into a slice of answers. Its default loops over the
//! single-ray queries ([`intersect_each`], [`occluded_each`]), so every structure (a student's
//! too) answers them; a structure that traces coherent rays together overrides them (the
//! structures of this workspace do, with the `rt-simd` crate's `Bundle`s and lane kernels),
//! and must answer every ray exactly as its single-ray query does: the conformance kit checks
//! it.
//!
//! A whole ray list goes through the bundles on all threads with the batch queries
//! ([`batch::intersect`], [`batch::occluded`]).
//! [`intersect_image`] and [`occluded_image`] do the same for rays that come in image order,
//! a row of pixels after another: they have the structure bundle them tile by tile
//! ([`Accel::intersect_bundle_ordered_with`]), where a run of the list would be a strip of one
//! row.
//!
//! # Counting
//! A bundle's walk reports one [`Stats::node_visit`] per node (or cell) the bundle enters,
//! whatever the number of its lanes, and with it [`Stats::bundle_lanes`]: how many lanes the
//! bundle carries and how many of them are active there. Node visits per ray then show what a
//! bundle saves, and [`Counters::lane_utilisation`](crate::Counters::lane_utilisation) how full
//! its steps were. Primitive tests count once per lane and primitive, as single rays count
//! them. A ray a bundle finishes alone (see [`Stats::single_ray`]) counts as a single ray.
//!
//! [`Stats::node_visit`]: crate::Stats::node_visit
//! [`Stats::bundle_lanes`]: crate::Stats::bundle_lanes
//! [`Stats::single_ray`]: crate::Stats::single_ray

pub use crate::accel::{intersect_each, occluded_each};
#[cfg(doc)]
use crate::batch;
use crate::{Accel, Hit, NoStats, Ray};

/// The side of the square tiles [`intersect_image`] bundles rays by, in pixels: an 8×8 tile is
/// the 64 rays of one full bundle.
pub const IMAGE_TILE: u32 = 8;

/// Where the rays of a list in image order lie in their image: what [`intersect_image`] and
/// [`occluded_image`] need to bundle them by tiles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Image<'a> {
    width: u32,
    pixels: Option<&'a [u32]>,
}

impl<'a> Image<'a> {
    /// One ray per pixel of an image `width` pixels wide, a row after another from the top
    /// left (as `rt_scene::Camera::primary_rays` makes them): ray `i` is pixel `i`.
    pub fn rows(width: u32) -> Self {
        Self {
            width,
            pixels: None,
        }
    }

    /// Rays of some pixels of an image `width` pixels wide: ray `i` belongs to pixel
    /// `pixels[i]` (`y · width + x`). In image order the indices never decrease along the list,
    /// as for the shadow rays of a frame's hits spawned in image order (any number of rays per
    /// pixel). Rays listed in another order are traced as they come, as [`batch::intersect`]
    /// traces them; rays past the end of `pixels` are not traced.
    pub fn pixels(width: u32, pixels: &'a [u32]) -> Self {
        Self {
            width,
            pixels: Some(pixels),
        }
    }
}

/// [`batch::intersect`] for rays in image order ([`Image`]): the same answers, in the same
/// slots, but each band of [`IMAGE_TILE`] pixel rows is bundled tile by tile
/// ([`Accel::intersect_bundle_ordered_with`]). A run of 64 rays of the list is a strip of 64
/// pixels of one row; a tile's rays lie eight times closer together, so a bundle's lanes share
/// more of their walk. A band whose rays barely walk (a few of its tiles, traced first, test
/// less than one primitive a ray) is traced as it comes instead, since gathering would cost
/// more than it saves. The bands are traced in parallel (with the `parallel` feature).
///
/// ```
/// use rt_core::{Accel, BruteForce, Ray, Triangle, bundle, glam::Vec3};
/// let tris = [Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::Y)];
/// let accel = BruteForce::build(&tris, &());
/// // A 40×30 image, a row of pixels after another.
/// let (width, height) = (40, 30);
/// let rays: Vec<Ray> = (0..width * height)
///     .map(|i| {
///         let (x, y) = ((i % width) as f32 / width as f32, (i / width) as f32 / height as f32);
///         Ray::new(Vec3::new(x - 0.5, y - 0.5, -1.0), Vec3::Z)
///     })
///     .collect();
/// let mut hits = vec![None; rays.len()];
/// bundle::intersect_image(&accel, &rays, bundle::Image::rows(width), &mut hits);
/// assert!(hits.iter().zip(&rays).all(|(h, r)| *h == accel.intersect(r)));
/// ```
pub fn intersect_image<A: Accel>(
    accel: &A,
    rays: &[Ray],
    image: Image<'_>,
    out: &mut [Option<Hit>],
) {
    by_tiles(
        rays,
        image,
        out,
        |r, o| accel.intersect_bundle_with(r, o, &mut NoStats),
        |r, order, o, w| accel.intersect_bundle_ordered_with(r, order, o, w),
        |r, order, o| accel.intersect_bundle_ordered_with(r, order, o, &mut NoStats),
    );
}

/// [`batch::occluded`] for rays in image order, bundled as [`intersect_image`] bundles them.
pub fn occluded_image<A: Accel>(accel: &A, rays: &[Ray], image: Image<'_>, out: &mut [bool]) {
    by_tiles(
        rays,
        image,
        out,
        |r, o| accel.occluded_bundle_with(r, o, &mut NoStats),
        |r, order, o, w| accel.occluded_bundle_ordered_with(r, order, o, w),
        |r, order, o| accel.occluded_bundle_ordered_with(r, order, o, &mut NoStats),
    );
}

/// One band of [`IMAGE_TILE`] pixel rows: its rays, their answers, and each ray's pixel.
struct Band<'r, 'o, T> {
    rays: &'r [Ray],
    out: &'o mut [T],
    /// The band's rays' pixels, or `None` for one ray per pixel from the band's first row on.
    pixels: Option<&'r [u32]>,
}

/// Splits the rays into bands and traces each band (in parallel) by tiles through `ordered`,
/// or as they come through `unordered` where tiles would not pay (see [`trace_band`]); rays
/// not in image order go to `unordered` as they come.
// PERF: the wide BVH's bundles, one thread (a one-thread rayon pool), the filled view at
// 1024×768, private harness, two runs, Mrays/s, `intersect_bundle` on rays in image order ->
// `intersect_image` on the same rays (-> `intersect_bundle` on the rays in 8×8 tiles, for
// reference): primary rays, the bunny 21.5 21.1 -> 33.8 33.7 (38.0), the teapot 41.8 42.0 ->
// 46.4 48.8 (54.9), the rocker arm 36.6 36.2 -> 45.9 46.0 (51.5), the cow 40.2 39.4 -> 45.9
// 48.0 (53.9), spot 46.0 44.7 -> 54.0 54.8 (65.6), the beetle 27.4 26.7 -> 40.5 40.7; their
// shadow rays, the bunny 13.8 13.7 -> 19.2 19.6 (21.9), the teapot 24.6 24.9 -> 23.3 28.1
// (35.5), the rocker arm 18.8 18.6 -> 21.6 24.7 (29.4), the cow 20.2 20.3 -> 24.7 26.2, spot
// 23.1 23.3 -> 26.3 28.3, the beetle 12.5 12.4 -> 17.5 17.1. The order for rows is made
// arithmetically: a counting sort there too cost the teapot's primary rays 48 -> 44.
fn by_tiles<T: Send>(
    rays: &[Ray],
    image: Image<'_>,
    out: &mut [T],
    unordered: impl Fn(&[Ray], &mut [T]) + Sync,
    probe: impl Fn(&[Ray], &[u32], &mut [T], &mut Work) + Sync,
    ordered: impl Fn(&[Ray], &[u32], &mut [T]) + Sync,
) {
    let listed = image.pixels.map_or(usize::MAX, <[u32]>::len);
    let n = rays.len().min(out.len()).min(listed);
    let (rays, out) = (&rays[..n], &mut out[..n]);
    let pixels = image.pixels.map(|p| &p[..n]);
    if pixels.is_some_and(|p| !p.is_sorted()) {
        crate::par::zip_chunks_mut(rays, out, crate::batch::CHUNK, &unordered);
        return;
    }
    let width = u64::from(image.width.max(1));
    let band_pixels = width * u64::from(IMAGE_TILE);
    let mut bands = Vec::new();
    let (mut rest_rays, mut rest_out, mut start) = (rays, out, 0);
    while !rest_rays.is_empty() {
        // The band's rays: up to its last pixel, which image order keeps together.
        let len = match pixels {
            Some(p) => {
                let band = u64::from(p[start]) / band_pixels;
                p[start..].partition_point(|&q| u64::from(q) / band_pixels <= band)
            }
            None => (band_pixels - start as u64 % band_pixels).min(rest_rays.len() as u64) as usize,
        };
        let (r, rays_after) = rest_rays.split_at(len);
        let (o, out_after) = std::mem::take(&mut rest_out).split_at_mut(len);
        bands.push(Band {
            rays: r,
            out: o,
            pixels: pixels.map(|p| &p[start..start + len]),
        });
        (rest_rays, rest_out, start) = (rays_after, out_after, start + len);
    }
    crate::par::for_each_mut(&mut bands, 1, |band| {
        trace_band(band, width, &unordered, &probe, &ordered);
    });
}

/// Tile columns of a band per tile [`trace_band`] probes.
const PROBE_EVERY: u64 = 32;

/// The primitive tests per ray of a band's probes below which [`trace_band`] traces the band as
/// it comes.
const PROBE_TESTS: u64 = 1;

/// Traces a band by tiles, unless its bundles walk too little to pay for gathering their rays.
/// A few tiles spread over the band are traced first (gathered, as every tile would be), and
/// their primitive tests counted. Below [`PROBE_TESTS`] a ray, the band is traced as it comes,
/// its probed tiles again with it; otherwise the rest of its tiles follow.
// PERF: gathering a bundle's rays costs some 4-6 ns a ray, more than a ray costs whose bundle
// misses everything. The wide BVH's bundles, one thread, the filled view at 1024×768, private
// harness, two runs, Mrays/s, shadow rays in image order as given (one run) -> through tiles,
// every band gathered -> probed: woody (every ray misses) 211 -> 85 86 -> 168 165; the
// alligator 219 -> 81 80 -> 180 165; fandisk 163 -> 77 79 -> 144 149; the teapot in a stadium
// 72 -> 51 52 -> 61 60. Where the walk is the work, probing costs nothing measurable: the
// bunny's shadow rays 19.3 19.9 -> 19.9 20.1, the teapot's 28.2 28.4 -> 29.7 30.2, primary
// rays on all 17 scenes within noise. Probing runs of the list as it comes instead of tiles,
// for listed pixels, cost 9-12% where bands go by tiles (left out of the order, the probed
// rays shift its later runs off the tiles; traced again, they cost more than they save).
fn trace_band<T>(
    band: &mut Band<'_, '_, T>,
    width: u64,
    unordered: impl Fn(&[Ray], &mut [T]),
    probe: impl Fn(&[Ray], &[u32], &mut [T], &mut Work),
    ordered: impl Fn(&[Ray], &[u32], &mut [T]),
) {
    let rows = Rows::of(band, width);
    let columns = width.div_ceil(u64::from(IMAGE_TILE));
    // Every PROBE_EVERY-th column from the middle of the first PROBE_EVERY (or of the band).
    let first = (PROBE_EVERY / 2).min(columns / 2);
    let probed = |c: u64| c % PROBE_EVERY == first;
    // The probed tiles in one call, so that their bundles share its start.
    let mut tiles = Vec::new();
    for c in (first..columns).step_by(PROBE_EVERY as usize) {
        rows.push_tile(c, &mut tiles);
    }
    let mut work = Work::default();
    probe(band.rays, &tiles, band.out, &mut work);
    // Probes that found no rays (a sparse list of pixels) leave the band as it comes too.
    if tiles.is_empty() || work.prim_tests < PROBE_TESTS * tiles.len() as u64 {
        unordered(band.rays, band.out);
        return;
    }
    let mut order = Vec::with_capacity(band.rays.len());
    rows.push_tiles(columns, |c| !probed(c), &mut order);
    ordered(band.rays, &order, band.out);
}

/// What [`trace_band`]'s probes count: primitive tests.
#[derive(Default)]
struct Work {
    prim_tests: u64,
}

impl crate::Stats for Work {
    #[inline(always)]
    fn node_visit(&mut self) {}
    #[inline(always)]
    fn prim_test(&mut self) {
        self.prim_tests += 1;
    }
}

/// Where each of a band's pixel rows lies among its rays.
struct Rows<'r> {
    width: u64,
    /// The band's first row's first pixel.
    first: u64,
    /// The pixels of the band's rays, or `None` for one ray per pixel from `first` on.
    pixels: Option<&'r [u32]>,
    /// Each row's rays: `rays[r]..rays[r + 1]`.
    rays: [usize; IMAGE_TILE as usize + 1],
}

impl<'r> Rows<'r> {
    fn of<T>(band: &Band<'r, '_, T>, width: u64) -> Self {
        let first = band.pixels.map_or(0, |p| u64::from(p[0]) / width * width);
        let mut rays = [0; IMAGE_TILE as usize + 1];
        for (r, end) in rays.iter_mut().enumerate().skip(1) {
            let end_pixel = first + r as u64 * width;
            *end = match band.pixels {
                Some(p) => search_from(p, end_pixel, p.len() * r / IMAGE_TILE as usize),
                None => end_pixel.min(band.rays.len() as u64) as usize,
            };
        }
        // The band's rays lie in its rows: bands are cut at every IMAGE_TILE-th row.
        debug_assert_eq!(rays[IMAGE_TILE as usize], band.rays.len());
        Self {
            width,
            first,
            pixels: band.pixels,
            rays,
        }
    }

    /// Appends the rays of the tile columns `0..columns` that `keep` keeps, column by column,
    /// each tile's rays a row after another.
    fn push_tiles(&self, columns: u64, keep: impl Fn(u64) -> bool, order: &mut Vec<u32>) {
        let Some(pixels) = self.pixels else {
            for c in (0..columns).filter(|&c| keep(c)) {
                self.push_tile(c, order);
            }
            return;
        };
        // Listed pixels: a cursor per row steps through its rays, a tile column at a time.
        // PERF: a counting sort over tile columns took 20-30% of the time of shadow rays that
        // all miss (woody): consecutive rays count into the same column, a chain through
        // memory. Bisecting each row for each tile's rays cost the teapot's shadow rays 7%.
        let mut next = self.rays;
        for c in 0..columns {
            let keep = keep(c);
            let x_end = ((c + 1) * u64::from(IMAGE_TILE)).min(self.width);
            for (r, (next, &to)) in next.iter_mut().zip(&self.rays[1..]).enumerate() {
                let from = *next;
                let end = self.first + r as u64 * self.width + x_end;
                while *next < to && u64::from(pixels[*next]) < end {
                    *next += 1;
                }
                if keep {
                    order.extend((from..*next).map(|i| i as u32));
                }
            }
        }
    }

    /// Appends tile column `c`'s rays, a row after another.
    fn push_tile(&self, c: u64, order: &mut Vec<u32>) {
        let tile = u64::from(IMAGE_TILE);
        let x = c * tile..((c + 1) * tile).min(self.width);
        for r in 0..IMAGE_TILE as usize {
            let (from, to) = (self.rays[r], self.rays[r + 1]);
            let row = self.first + r as u64 * self.width;
            match self.pixels {
                // One ray per pixel: ray i is pixel `first + i`.
                None => {
                    let end = (row + x.end).min(to as u64);
                    order.extend((row + x.start..end).map(|i| i as u32));
                }
                // Listed pixels: the row's lie together, sorted; the tile's are searched from
                // where they would lie if the row's were spread evenly.
                // PERF: bisecting the row instead waited on memory: 6% of the time of shadow
                // rays that all miss (woody), in a list the band has not read yet.
                Some(p) => {
                    let row_rays = &p[from..to];
                    let guess = row_rays.len() * x.start as usize / self.width as usize;
                    let a = search_from(row_rays, row + x.start, guess);
                    let b = a + row_rays[a..].partition_point(|&q| u64::from(q) < row + x.end);
                    order.extend((from + a..from + b).map(|i| i as u32));
                }
            }
        }
    }
}

/// The first index of the sorted `p` whose entry is at least `key` (`p.len()` if none), found
/// by steps doubling outwards from `guess` and a bisection of the last step: a few loads near
/// a good guess, and never more than twice a bisection's.
fn search_from(p: &[u32], key: u64, guess: usize) -> usize {
    let below = |i: usize| u64::from(p[i]) < key;
    let (n, g) = (p.len(), guess.min(p.len()));
    // The answer lies in lo..=hi.
    let (mut lo, mut hi, mut step) = (0, n, 1);
    if g < n && below(g) {
        lo = g + 1;
        while lo + step - 1 < n {
            let i = lo + step - 1;
            if !below(i) {
                hi = i;
                break;
            }
            lo = i + 1;
            step *= 2;
        }
    } else {
        hi = g;
        while step <= hi {
            let i = hi - step;
            if below(i) {
                lo = i + 1;
                break;
            }
            hi = i;
            step *= 2;
        }
    }
    lo + p[lo..hi].partition_point(|&q| u64::from(q) < key)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::glam::Vec3;
    use crate::{BruteForce, Triangle};
    use std::sync::Mutex;

    /// A `width` × `height` image's rays, a row after another, towards two triangles that
    /// cover part of it (so some rays hit and some miss).
    fn image(width: u32, height: u32) -> (Vec<Ray>, BruteForce<Triangle>) {
        let tris = [
            Triangle::new(
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::Y,
            ),
            Triangle::new(Vec3::new(-1.0, 0.5, 1.0), Vec3::new(0.2, 0.5, 1.0), Vec3::Z),
        ];
        let rays = (0..width * height)
            .map(|i| {
                let x = (i % width) as f32 / width as f32 * 3.0 - 1.5;
                let y = (i / width) as f32 / height as f32 * 3.0 - 1.5;
                Ray::new(Vec3::new(x, y, -1.0), Vec3::new(0.1, 0.05, 1.0))
            })
            .collect();
        (rays, BruteForce::build(&tris, &()))
    }

    /// What `by_tiles` did with one band.
    #[derive(Debug, Default, PartialEq)]
    struct Handed {
        /// The probed tiles' rays, in the order handed over.
        probed: Vec<u32>,
        /// The rest of the band's rays in the order handed over, if it went by tiles.
        ordered: Option<Vec<u32>>,
        /// How many rays went as they come (the whole band, when it did).
        unordered: usize,
    }

    /// What `by_tiles` hands over, band by band (the bands in order), with probes that count
    /// `tests` primitive tests per ray.
    fn handed(rays: &[Ray], image: Image<'_>, tests: u64) -> Vec<Handed> {
        let seen = Mutex::new(std::collections::BTreeMap::<usize, Handed>::new());
        let unordered = Mutex::new(Vec::new());
        let band = |r: &[Ray]| r.as_ptr() as usize;
        let mut out = vec![0u8; rays.len()];
        by_tiles(
            rays,
            image,
            &mut out,
            |r, _| unordered.lock().unwrap().push((band(r), r.len())),
            |r, order, _, work| {
                for _ in 0..tests * order.len() as u64 {
                    crate::Stats::prim_test(work);
                }
                let mut seen = seen.lock().unwrap();
                seen.entry(band(r)).or_default().probed.extend(order);
            },
            |r, order, _| {
                let mut seen = seen.lock().unwrap();
                let handed = seen.entry(band(r)).or_default();
                assert!(handed.ordered.replace(order.to_vec()).is_none());
            },
        );
        // Every band is probed first: a slice traced as it comes belongs to the band probed
        // last before it.
        let mut seen = seen.into_inner().unwrap();
        for (at, len) in unordered.into_inner().unwrap() {
            let (_, band) = seen.range_mut(..=at).next_back().expect("a probed band");
            band.unordered += len;
        }
        seen.into_values().collect()
    }

    /// A band's tiles in order, each a row after another: rows `y0..y1` of a `width`-pixel
    /// image, numbered from the band's first pixel.
    fn tiles(width: u32, (y0, y1): (u32, u32)) -> Vec<Vec<u32>> {
        (0..width.div_ceil(8))
            .map(|c| {
                let mut tile = Vec::new();
                for y in y0..y1 {
                    for x in 8 * c..(8 * c + 8).min(width) {
                        tile.push((y - y0) * width + x);
                    }
                }
                tile
            })
            .collect()
    }

    #[test]
    fn rows_are_handed_over_by_tiles_of_eight_by_eight() {
        let (width, height) = (20, 12);
        let (rays, _) = image(width, height);
        // Band 0 holds rows 0..8, band 1 rows 8..12; tiles start at columns 0, 8 and 16; the
        // band's middle tile is probed first.
        let mut want = Vec::new();
        for rows in [(0, 8), (8, 12)] {
            let tiles = tiles(width, rows);
            want.push(Handed {
                probed: tiles[1].clone(),
                ordered: Some([&tiles[0][..], &tiles[2][..]].concat()),
                unordered: 0,
            });
        }
        assert_eq!(handed(&rays, Image::rows(width), 1), want);
        // A last row cut short: its missing pixels are not listed.
        let last = &handed(&rays[..rays.len() - 5], Image::rows(width), 1)[1];
        assert_eq!(last.probed.len() + last.ordered.as_ref().unwrap().len(), 75);
    }

    #[test]
    fn bands_whose_probes_test_little_go_as_they_come() {
        let (width, height) = (600, 9);
        let (rays, _) = image(width, height);
        // 75 tile columns: every 32nd is probed, from the 16th.
        let tiles = tiles(width, (0, 8));
        let probed = [&tiles[16][..], &tiles[48][..]].concat();
        let got = handed(&rays, Image::rows(width), 0);
        let want = [
            Handed {
                probed,
                ordered: None,
                unordered: 8 * width as usize,
            },
            Handed {
                // One row: the same tile columns, a row of each.
                probed: (128..136).chain(384..392).collect(),
                ordered: None,
                unordered: width as usize,
            },
        ];
        assert_eq!(got, want);
        // One test a ray is enough to go by tiles.
        assert!(
            handed(&rays, Image::rows(width), 1)
                .iter()
                .all(|h| h.ordered.is_some())
        );
    }

    #[test]
    fn listed_pixels_are_handed_over_by_tile_columns_keeping_their_order() {
        let (width, height) = (200, 12);
        let (rays, _) = image(width, height);
        // Every third pixel, and pixel 25 twice; rays and pixels pair up in image order.
        let mut pixels: Vec<u32> = (0..width * height).step_by(3).collect();
        pixels.insert(9, 25);
        let rays = &rays[..pixels.len()];
        let split = pixels.partition_point(|&p| p < 8 * width);
        for tests in [0, 1] {
            let got = handed(rays, Image::pixels(width, &pixels), tests);
            assert_eq!(got.len(), 2);
            for (band, (first, last)) in got.iter().zip([(0, split), (split, pixels.len())]) {
                // The probe: tile column 12 of 25, its rays in the pixels' order.
                let m = last - first;
                let column = |i: &u32| pixels[first + *i as usize] % width / 8;
                let probed: Vec<u32> = (0..m as u32).filter(|i| column(i) == 12).collect();
                assert!(!probed.is_empty());
                assert_eq!(band.probed, probed);
                if tests == 0 {
                    // The whole band as it comes, the probed tile again with it.
                    assert_eq!((band.ordered.as_ref(), band.unordered), (None, m));
                    continue;
                }
                // The rest by tile columns, each keeping the pixels' order.
                let mut want: Vec<u32> =
                    (0..m as u32).filter(|i| !band.probed.contains(i)).collect();
                want.sort_by_key(column);
                assert_eq!(band.ordered.as_ref(), Some(&want));
            }
        }
    }

    #[test]
    fn searching_from_a_guess_finds_what_bisection_finds() {
        // Sorted lists: empty, one entry, runs of equal entries, gaps, and a pseudo-random one.
        let mut state = 7u32;
        let mut random: Vec<u32> = (0..300)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                state >> 22
            })
            .collect();
        random.sort_unstable();
        let lists = [
            vec![],
            vec![5],
            vec![1, 1, 1, 2, 2, 9, 9, 9, 9, 40],
            (0..100).map(|i| i * 3).collect(),
            random,
        ];
        for p in &lists {
            let max = p.last().map_or(0, |&q| u64::from(q));
            for key in 0..=max + 2 {
                let want = p.partition_point(|&q| u64::from(q) < key);
                for guess in 0..=p.len() + 2 {
                    assert_eq!(search_from(p, key, guess), want, "{key} from {guess}");
                }
            }
        }
    }

    #[test]
    fn image_queries_answer_every_ray_in_its_slot() {
        for (width, height) in [(37, 21), (8, 8), (1, 5), (64, 3)] {
            let (rays, accel) = image(width, height);
            let single: Vec<_> = rays.iter().map(|r| accel.intersect(r)).collect();
            let blocked: Vec<_> = rays.iter().map(|r| accel.occluded(r)).collect();
            let mut hits = vec![None; rays.len()];
            intersect_image(&accel, &rays, Image::rows(width), &mut hits);
            assert_eq!(hits, single, "{width}×{height}");
            let mut got = vec![false; rays.len()];
            occluded_image(&accel, &rays, Image::rows(width), &mut got);
            assert_eq!(got, blocked, "{width}×{height}");
            if width == 37 {
                // Hits and misses both, so that a misplaced answer shows.
                assert!(hits.iter().any(Option::is_some) && hits.iter().any(Option::is_none));
            }
        }
    }

    #[test]
    fn listed_pixels_in_any_order_and_short_slices_answer_exactly() {
        let (width, height) = (37, 21);
        let (rays, accel) = image(width, height);
        let single: Vec<_> = rays.iter().map(|r| accel.intersect(r)).collect();
        let marker = Some(Hit {
            prim: 9,
            t: -1.0,
            u: 0.0,
            v: 0.0,
        });
        // Sorted, unsorted (traced as they come), and pixels beyond the image's width.
        let sorted: Vec<u32> = (0..rays.len() as u32).collect();
        let unsorted: Vec<u32> = sorted.iter().rev().copied().collect();
        let wide: Vec<u32> = sorted.iter().map(|&p| p * 3).collect();
        for pixels in [&sorted, &unsorted, &wide] {
            let mut hits = vec![marker; rays.len()];
            intersect_image(&accel, &rays, Image::pixels(width, pixels), &mut hits);
            assert_eq!(hits, single);
        }
        // Fewer pixels than rays: the rays past them keep their slots' values; fewer slots
        // than rays: the first rays are answered.
        let mut hits = vec![marker; rays.len()];
        intersect_image(
            &accel,
            &rays,
            Image::pixels(width, &sorted[..100]),
            &mut hits,
        );
        assert_eq!(&hits[..100], &single[..100]);
        assert!(hits[100..].iter().all(|&h| h == marker));
        let mut short = vec![marker; 50];
        intersect_image(&accel, &rays, Image::rows(width), &mut short);
        assert_eq!(&short[..], &single[..50]);
        // A width of zero is read as one pixel.
        let mut hits = vec![marker; rays.len()];
        intersect_image(&accel, &rays, Image::rows(0), &mut hits);
        assert_eq!(hits, single);
    }
}
