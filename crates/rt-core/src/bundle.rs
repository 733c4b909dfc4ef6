//! Many rays in one call: what [`Accel::intersect_bundle`] and [`Accel::occluded_bundle`]
//! promise, the loops behind their defaults, and whole frames on all threads.
//!
//! A bundle query answers a slice of rays into a slice of answers. Its default loops over the
//! single-ray queries ([`intersect_each`], [`occluded_each`]), so every structure (a student's
//! too) answers them; a structure that traces coherent rays together overrides them (the
//! structures of this workspace do, with the `rt-simd` crate's `Bundle`s and lane kernels),
//! and must answer every ray exactly as its single-ray query does: the conformance kit checks
//! it.
//!
//! [`intersect_frame`] and [`occluded_frame`] trace a whole ray list in tasks on rayon's
//! threads (with the `parallel` feature; in order on the calling thread without it).
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
use crate::{Accel, Hit, NoStats, Ray};

/// Rays per task of [`intersect_frame`] and [`occluded_frame`]: sixteen full bundles of 64
/// rays, enough to amortise a task's start, few enough to balance a frame over the threads.
pub const FRAME_TASK: usize = 1024;

/// [`Accel::intersect_bundle`] over a whole ray list (a frame, a batch of queries), in tasks of
/// [`FRAME_TASK`] rays on rayon's threads with the `parallel` feature. `out` gets as many answers
/// as both slices have slots, each exactly the single-ray answer.
///
/// ```
/// use rt_core::{Accel, BruteForce, Ray, Triangle, bundle, glam::Vec3};
/// let tris = [Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::Y)];
/// let accel = BruteForce::build(&tris, &());
/// let rays: Vec<Ray> = (0..1000)
///     .map(|i| Ray::new(Vec3::new(i as f32 / 1000.0 - 0.5, 0.0, -1.0), Vec3::Z))
///     .collect();
/// let mut hits = vec![None; rays.len()];
/// bundle::intersect_frame(&accel, &rays, &mut hits);
/// assert!(hits.iter().all(|h| h.is_some_and(|h| h.prim == 0 && h.t == 1.0)));
/// ```
pub fn intersect_frame<A: Accel>(accel: &A, rays: &[Ray], out: &mut [Option<Hit>]) {
    crate::par::zip_chunks_mut(rays, out, FRAME_TASK, |r, o| {
        accel.intersect_bundle_with(r, o, &mut NoStats)
    });
}

/// [`Accel::occluded_bundle`] over a whole ray list, as [`intersect_frame`] does.
pub fn occluded_frame<A: Accel>(accel: &A, rays: &[Ray], out: &mut [bool]) {
    crate::par::zip_chunks_mut(rays, out, FRAME_TASK, |r, o| {
        accel.occluded_bundle_with(r, o, &mut NoStats)
    });
}

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
    /// pixel). Rays listed in another order are traced as they come, as [`intersect_frame`]
    /// traces them; rays past the end of `pixels` are not traced.
    pub fn pixels(width: u32, pixels: &'a [u32]) -> Self {
        Self {
            width,
            pixels: Some(pixels),
        }
    }
}

/// [`intersect_frame`] for rays in image order ([`Image`]): the same answers, in the same
/// slots, but each band of [`IMAGE_TILE`] pixel rows is bundled tile by tile
/// ([`Accel::intersect_bundle_ordered_with`]). A run of 64 rays of the list is a strip of 64
/// pixels of one row; a tile's rays lie eight times closer together, so a bundle's lanes share
/// more of their walk. The bands are traced in parallel (with the `parallel` feature).
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
        |r, order, o| accel.intersect_bundle_ordered_with(r, order, o, &mut NoStats),
    );
}

/// [`occluded_frame`] for rays in image order, bundled as [`intersect_image`] bundles them.
pub fn occluded_image<A: Accel>(accel: &A, rays: &[Ray], image: Image<'_>, out: &mut [bool]) {
    by_tiles(
        rays,
        image,
        out,
        |r, o| accel.occluded_bundle_with(r, o, &mut NoStats),
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

/// Splits the rays into bands and traces each band (in parallel) by tiles through `ordered`;
/// rays not in image order go to `unordered` as they come.
// PERF: the wide BVH's bundles, one thread (a one-thread rayon pool), the filled view at
// 1024×768, private harness, two runs, Mrays/s, `intersect_bundle` on rays in image order ->
// `intersect_image` on the same rays (-> `intersect_bundle` on the rays in 8×8 tiles, for
// reference): primary rays, the bunny 21.5 21.1 -> 33.8 33.7 (38.0), the teapot 41.8 42.0 ->
// 46.4 48.8 (54.9), the rocker arm 36.6 36.2 -> 45.9 46.0 (51.5), the cow 40.2 39.4 -> 45.9
// 48.0 (53.9), spot 46.0 44.7 -> 54.0 54.8 (65.6), the beetle 27.4 26.7 -> 40.5 40.7; their
// shadow rays, the bunny 13.8 13.7 -> 19.2 19.6 (21.9), the teapot 24.6 24.9 -> 23.3 28.1
// (35.5), the rocker arm 18.8 18.6 -> 21.6 24.7 (29.4), the cow 20.2 20.3 -> 24.7 26.2, spot
// 23.1 23.3 -> 26.3 28.3, the beetle 12.5 12.4 -> 17.5 17.1. It loses where the rays cost
// next to nothing: the shadow rays of woody and the alligator, which all miss (151-213 Mrays/s
// as given), 80-83 and 52-81; gathering costs some 6 ns a ray, more than such a ray. The order
// for rows is made arithmetically: a counting sort there too cost the teapot's primary rays
// 48 -> 44.
fn by_tiles<T: Send>(
    rays: &[Ray],
    image: Image<'_>,
    out: &mut [T],
    unordered: impl Fn(&[Ray], &mut [T]) + Sync,
    ordered: impl Fn(&[Ray], &[u32], &mut [T]) + Sync,
) {
    let listed = image.pixels.map_or(usize::MAX, <[u32]>::len);
    let n = rays.len().min(out.len()).min(listed);
    let (rays, out) = (&rays[..n], &mut out[..n]);
    let pixels = image.pixels.map(|p| &p[..n]);
    if pixels.is_some_and(|p| !p.is_sorted()) {
        crate::par::zip_chunks_mut(rays, out, FRAME_TASK, &unordered);
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
        let order = tile_order(band, width);
        ordered(band.rays, &order, band.out);
    });
}

/// A band's rays in tile order: tile column by tile column, each tile's rays a row after
/// another, as `rt_scene::Camera::tiled_rays` lists them.
fn tile_order<T>(band: &Band<'_, '_, T>, width: u64) -> Vec<u32> {
    let tile = u64::from(IMAGE_TILE);
    let m = band.rays.len();
    let Some(pixels) = band.pixels else {
        // Ray i is pixel `first + i`, and the band starts a row: the order is arithmetic.
        let rows = (m as u64).div_ceil(width);
        let mut order = Vec::with_capacity(m);
        for x0 in (0..width).step_by(tile as usize) {
            for y in 0..rows {
                for x in x0..(x0 + tile).min(width) {
                    let i = y * width + x;
                    if i < m as u64 {
                        order.push(i as u32);
                    }
                }
            }
        }
        return order;
    };
    // Listed pixels: sorted by tile column with a counting sort, stably, so each tile's rays
    // keep their order (a row after another in image order).
    let (w, t) = (width as u32, IMAGE_TILE);
    // Each ray's tile column, with one division each.
    let column: Vec<u32> = pixels.iter().map(|&q| q % w / t).collect();
    // `next[c]`: where tile column c's next ray goes.
    let mut next = vec![0u32; width.div_ceil(tile) as usize + 1];
    for &c in &column {
        next[c as usize + 1] += 1;
    }
    for c in 1..next.len() {
        next[c] += next[c - 1];
    }
    let mut order = vec![0u32; m];
    for (i, &c) in column.iter().enumerate() {
        order[next[c as usize] as usize] = i as u32;
        next[c as usize] += 1;
    }
    order
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

    /// The orders `by_tiles` hands over, band by band (the bands in order).
    fn orders(rays: &[Ray], image: Image<'_>) -> Vec<Vec<u32>> {
        let seen = Mutex::new(Vec::new());
        let mut out = vec![0u8; rays.len()];
        by_tiles(
            rays,
            image,
            &mut out,
            |_, _| panic!("rays in image order are traced by tiles"),
            |r, order, _| {
                seen.lock()
                    .unwrap()
                    .push((r.as_ptr() as usize, order.to_vec()))
            },
        );
        let mut seen = seen.into_inner().unwrap();
        seen.sort_unstable();
        seen.into_iter().map(|(_, order)| order).collect()
    }

    #[test]
    fn rows_are_handed_over_by_tiles_of_eight_by_eight() {
        let (width, height) = (20, 12);
        let (rays, _) = image(width, height);
        // Band 0 holds rows 0..8, band 1 rows 8..12; tiles start at columns 0, 8 and 16.
        let mut want = Vec::new();
        for (y0, y1) in [(0, 8), (8, 12)] {
            let mut band = Vec::new();
            for x0 in [0, 8, 16] {
                for y in y0..y1 {
                    for x in x0..(x0 + 8).min(width) {
                        band.push((y - y0) * width + x);
                    }
                }
            }
            want.push(band);
        }
        assert_eq!(orders(&rays, Image::rows(width)), want);
        // A last row cut short: its missing pixels are not listed.
        assert_eq!(
            orders(&rays[..rays.len() - 5], Image::rows(width))[1].len(),
            75
        );
    }

    #[test]
    fn listed_pixels_are_handed_over_by_tile_columns_keeping_their_order() {
        let (width, height) = (20, 12);
        let (rays, _) = image(width, height);
        // Every third pixel, and pixel 25 twice; rays and pixels pair up in image order.
        let mut pixels: Vec<u32> = (0..width * height).step_by(3).collect();
        pixels.insert(9, 25);
        let rays = &rays[..pixels.len()];
        let got = orders(rays, Image::pixels(width, &pixels));
        assert_eq!(got.len(), 2);
        let split = pixels.partition_point(|&p| p < 8 * width);
        for (band, (first, last)) in got.iter().zip([(0, split), (split, pixels.len())]) {
            let mut want: Vec<u32> = (0..(last - first) as u32).collect();
            want.sort_by_key(|&i| pixels[first + i as usize] % width / 8);
            assert_eq!(band, &want);
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
