//! Images, tiled parallel rendering and PNG output.

use crate::RenderScene;
use crate::whitted::Context;
use rayon::prelude::*;
use rt_core::DynAccel;
use rt_core::glam::Vec3;
use rt_core::{Ray, Shape};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// An 8-bit sRGB image, row by row from the top left.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels.
    pub pixels: Vec<[u8; 3]>,
}

/// The largest image side [`Image::new`] and [`render`] accept: 16384 pixels.
pub const MAX_SIDE: u32 = 1 << 14;

/// A size or a file the renderer cannot use.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ImageError {
    /// A side of zero, or larger than [`MAX_SIDE`].
    BadSize {
        /// The width asked for.
        width: u32,
        /// The height asked for.
        height: u32,
    },
    /// The PNG could not be written.
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ImageError::BadSize { width, height } => write!(
                f,
                "image size {width}×{height} is not usable: each side must be 1 to {MAX_SIDE} pixels"
            ),
            ImageError::Write { path, message } => {
                write!(f, "{}: cannot write PNG: {message}", path.display())
            }
        }
    }
}

impl std::error::Error for ImageError {}

impl Image {
    /// A black image.
    ///
    /// # Errors
    /// [`ImageError::BadSize`] for a zero side or one above [`MAX_SIDE`].
    pub fn new(width: u32, height: u32) -> Result<Self, ImageError> {
        if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
            return Err(ImageError::BadSize { width, height });
        }
        Ok(Self {
            width,
            height,
            pixels: vec![[0; 3]; width as usize * height as usize],
        })
    }

    /// The pixel at column `x`, row `y`.
    ///
    /// # Panics
    /// If the pixel is outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(x < self.width && y < self.height, "pixel outside the image");
        self.pixels[(y * self.width + x) as usize]
    }

    /// Writes the image as a PNG file.
    ///
    /// # Errors
    /// [`ImageError::Write`] naming the file when it cannot be created or written.
    pub fn save_png(&self, path: &Path) -> Result<(), ImageError> {
        // Encoded in memory and written in one call, so that every error of the write (a full
        // disk included) is reported, not lost in a buffered writer's drop.
        let write = || -> Result<(), png::EncodingError> {
            let mut bytes = Vec::new();
            let mut encoder = png::Encoder::new(&mut bytes, self.width, self.height);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            let mut writer = encoder.write_header()?;
            writer.write_image_data(self.pixels.as_flattened())?;
            writer.finish()?;
            Ok(std::fs::write(path, &bytes)?)
        };
        write().map_err(|e| ImageError::Write {
            path: path.to_owned(),
            message: match e {
                png::EncodingError::IoError(io) => io.to_string(),
                other => other.to_string(),
            },
        })
    }
}

/// How to render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Rays along one path, the primary ray included: 1 shades primary hits with shadows only,
    /// each further level adds one bounce of mirror or glass.
    pub depth: u32,
}

impl Default for RenderOptions {
    /// 1024×768, depth 5.
    fn default() -> Self {
        Self {
            width: 1024,
            height: 768,
            depth: 5,
        }
    }
}

/// Side of the square tiles rendered in parallel.
///
/// PERF: a tile's rays stay close together and so share the cache lines of the nodes they
/// visit; 16 keeps ~3000 tiles in a 1024×768 image, plenty for rayon to balance two threads.
pub const TILE: u32 = 16;

/// Renders `scene`, whose [`RenderScene::shapes`] `tracer` was built over, one ray through each
/// pixel centre, tiles in parallel on rayon's current pool. `progress` is called with the tiles
/// done and the total after each tile (from any thread).
///
/// # Errors
/// [`ImageError::BadSize`] for an unusable size.
///
/// ```
/// use rt_core::Accel;
/// use rt_render::{RenderOptions, RenderScene, render};
/// let scene = RenderScene::whitted();
/// let accel = rt_core::BruteForce::build(&scene.shapes()[..2000], &Default::default());
/// let options = RenderOptions { width: 8, height: 6, depth: 2 };
/// let image = render(&scene, &scene.shapes(), &accel, &options, &|_, _| {}).unwrap();
/// assert_eq!(image.pixels.len(), 48);
/// ```
pub fn render(
    scene: &RenderScene,
    shapes: &[Shape],
    tracer: &dyn DynAccel<Shape>,
    options: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Image, ImageError> {
    let ctx = Context {
        scene,
        shapes,
        tracer,
        max_depth: options.depth.max(1),
    };
    let raster = scene.camera.raster(options.width, options.height);
    let pixels = per_tile(options.width, options.height, progress, |x0, y0, w, h| {
        let mut out = vec![[0u8; 3]; (w * h) as usize];
        // Block by block, so that each block's primary rays make one coherent bundle.
        let at: Vec<usize> = block_order(w, h)
            .map(|(x, y)| (y * w + x) as usize)
            .collect();
        let rays: Vec<Ray> = at
            .iter()
            .map(|&i| {
                let (x, y) = (x0 + i as u32 % w, y0 + i as u32 / w);
                raster.ray(x as f32 + 0.5, y as f32 + 0.5)
            })
            .collect();
        for (&i, color) in at.iter().zip(ctx.radiance_bundle(&rays)) {
            out[i] = encode(color);
        }
        out
    })?;
    Ok(Image {
        width: options.width,
        height: options.height,
        pixels,
    })
}

/// Side of the square blocks of pixels whose primary rays [`render`] traces as one bundle
/// (64 rays, a full bundle of `rt_simd::BUNDLE_LANES`).
const BLOCK: u32 = 8;

/// Fills a `width × height` image by calling `pixel(x, y)` for every pixel, tiles in parallel.
pub(crate) fn per_pixel<T: Copy + Default + Send>(
    width: u32,
    height: u32,
    progress: &(dyn Fn(usize, usize) + Sync),
    pixel: impl Fn(u32, u32) -> T + Sync,
) -> Result<Vec<T>, ImageError> {
    per_tile(width, height, progress, |x0, y0, w, h| {
        let mut out = Vec::with_capacity((w * h) as usize);
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                out.push(pixel(x, y));
            }
        }
        out
    })
}

/// Fills a `width × height` image tile by tile in parallel: `tile(x0, y0, w, h)` returns the
/// `w × h` pixels of the tile at `(x0, y0)`, row by row.
/// The pixels `(x, y)` of a `w × h` tile in blocks of [`BLOCK`]×[`BLOCK`], each block row by
/// row: a block's primary rays make one coherent bundle.
pub(crate) fn block_order(w: u32, h: u32) -> impl Iterator<Item = (u32, u32)> {
    (0..h).step_by(BLOCK as usize).flat_map(move |by| {
        (0..w).step_by(BLOCK as usize).flat_map(move |bx| {
            (by..(by + BLOCK).min(h))
                .flat_map(move |y| (bx..(bx + BLOCK).min(w)).map(move |x| (x, y)))
        })
    })
}

pub(crate) fn per_tile<T: Copy + Default + Send>(
    width: u32,
    height: u32,
    progress: &(dyn Fn(usize, usize) + Sync),
    tile: impl Fn(u32, u32, u32, u32) -> Vec<T> + Sync,
) -> Result<Vec<T>, ImageError> {
    Image::new(width, height)?;
    let (tiles_x, tiles_y) = (width.div_ceil(TILE), height.div_ceil(TILE));
    let total = (tiles_x * tiles_y) as usize;
    let done = AtomicUsize::new(0);
    let tiles: Vec<(u32, u32, Vec<T>)> = (0..total as u32)
        .into_par_iter()
        .map(|k| {
            let (x0, y0) = ((k % tiles_x) * TILE, (k / tiles_x) * TILE);
            let (w, h) = (TILE.min(width - x0), TILE.min(height - y0));
            let out = tile(x0, y0, w, h);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            (x0, y0, out)
        })
        .collect();
    let mut pixels = vec![T::default(); width as usize * height as usize];
    for (x0, y0, out) in tiles {
        let w = (TILE.min(width - x0)) as usize;
        for (row, chunk) in out.chunks(w).enumerate() {
            let start = (y0 as usize + row) * width as usize + x0 as usize;
            pixels[start..start + w].copy_from_slice(chunk);
        }
    }
    Ok(pixels)
}

/// Linear RGB to 8-bit sRGB, clamped.
pub fn encode(linear: Vec3) -> [u8; 3] {
    linear.to_array().map(|c| {
        let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
        let s = if c <= 0.003_130_8 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5) as u8
    })
}
