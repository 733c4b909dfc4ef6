//! A pinhole camera: the rays of an image, one per pixel or through any point of a pixel.
//!
//! This is the camera a renderer needs: frame a mesh's box, then ask for the ray through each
//! pixel (or any sub-pixel sample) and trace it through any structure.
//!
//! ```
//! use rt_core::{Accel, BruteForce, Triangle, glam::Vec3};
//! use rt_scene::Camera;
//!
//! let tris = [Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::Y)];
//! let accel = BruteForce::build(&tris, &());
//! let (width, height) = (64, 48);
//! let camera = Camera::framing(&accel.bounds(), width, height); // the box fills the image
//! let raster = camera.raster(width, height);
//! let mut image = vec![0u8; (width * height) as usize];
//! for y in 0..height {
//!     for x in 0..width {
//!         let ray = raster.ray(x as f32 + 0.5, y as f32 + 0.5); // the pixel's centre
//!         image[(y * width + x) as usize] = if accel.intersect(&ray).is_some() { 255 } else { 0 };
//!     }
//! }
//! assert!(image.contains(&255) && image.contains(&0));
//! ```

use glam::Vec3;
use rt_core::{Aabb, Ray};

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point the camera looks at.
    pub target: Vec3,
    /// Approximate up direction.
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
}

impl Camera {
    /// A camera that looks at the box from the front (+z), slightly from above, with a 40°
    /// vertical field of view, as close as it can while every corner of the box stays in a
    /// `width × height` image.
    pub fn framing(bounds: &Aabb, width: u32, height: u32) -> Self {
        Self::framing_from(bounds, Vec3::new(0.15, 0.3, 1.0), width, height)
    }

    /// A camera that looks at the box's centre from [`Camera::framing`]'s direction, at 1.5 times
    /// the radius of the box's bounding sphere, with the same 40° field of view: the box fills
    /// the image and overflows it at the edges, so most primary rays enter the box and a large
    /// share of them hit the mesh. Benchmarks time traversal on this view; on the framing view
    /// most rays leave at the box test, which times the cost of a call.
    pub fn filled(bounds: &Aabb) -> Self {
        let center = bounds.center();
        let back = Vec3::new(0.15, 0.3, 1.0).normalize();
        let radius = 0.5 * bounds.extent().length();
        Self {
            eye: center + back * (1.5 * radius).max(1e-6),
            target: center,
            up: Vec3::Y,
            vfov_deg: 40.0,
        }
    }

    /// [`Camera::framing`] from the direction `back` (from the box's centre towards the eye;
    /// need not be unit length): a field of instances on the ground, say, seen from above.
    pub fn framing_from(bounds: &Aabb, back: Vec3, width: u32, height: u32) -> Self {
        let vfov_deg = 40.0f32;
        let center = bounds.center();
        let back = back.try_normalize().unwrap_or(Vec3::Z);
        let forward = -back;
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let tan_v = (0.5 * vfov_deg.to_radians()).tan();
        let tan_h = tan_v * width as f32 / height.max(1) as f32;
        // A corner at offset c from the centre is at depth d + c·forward; it is in view when its
        // sideways offsets are within depth · tan of the half angles.
        let mut dist = 1e-6f32;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 {
                    bounds.min.x
                } else {
                    bounds.max.x
                },
                if i & 2 == 0 {
                    bounds.min.y
                } else {
                    bounds.max.y
                },
                if i & 4 == 0 {
                    bounds.min.z
                } else {
                    bounds.max.z
                },
            ) - center;
            let depth = corner.dot(forward);
            dist = dist
                .max(corner.dot(up).abs() / tan_v - depth)
                .max(corner.dot(right).abs() / tan_h - depth);
        }
        // A small margin so the silhouette does not touch the image border.
        let eye = center + back * dist * 1.05;
        Self {
            eye,
            target: center,
            up: Vec3::Y,
            vfov_deg,
        }
    }

    /// The camera set up for a `width × height` image: it gives the ray through any point of the
    /// image plane ([`Raster::ray`]), for renderers that sample pixels one at a time, several
    /// times, or in tiles.
    pub fn raster(&self, width: u32, height: u32) -> Raster {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let tan = (0.5 * self.vfov_deg.to_radians()).tan();
        Raster {
            eye: self.eye,
            forward,
            right,
            up,
            tan,
            aspect: width as f32 / height.max(1) as f32,
            width: width as f32,
            height: height as f32,
        }
    }

    /// One ray through the centre of each pixel of a `width × height` image, row by row from the
    /// top left.
    pub fn primary_rays(&self, width: u32, height: u32) -> Vec<Ray> {
        let raster = self.raster(width, height);
        let mut rays = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                rays.push(raster.ray(x as f32 + 0.5, y as f32 + 0.5));
            }
        }
        rays
    }
}

impl Camera {
    /// One ray through the centre of each pixel of a `width × height` image, tile by tile: the
    /// image cut into `tile.0 × tile.1` pixel tiles (narrower at the right and bottom edges),
    /// tiles row by row from the top left, and each tile's pixels row by row. Neighbouring rays
    /// then sit side by side in the list, as a bundle query wants them
    /// ([`rt_core::Accel::intersect_bundle`]); an 8×8 tile fills one 64-lane bundle. Returns the
    /// rays and, for each, its pixel index `y · width + x`.
    ///
    /// ```
    /// use rt_core::{Aabb, glam::Vec3};
    /// use rt_scene::Camera;
    /// let camera = Camera::framing(&Aabb::new(Vec3::ZERO, Vec3::ONE), 20, 10);
    /// let (rays, pixels) = camera.tiled_rays(20, 10, (8, 8));
    /// let rows = camera.primary_rays(20, 10);
    /// assert_eq!(rays.len(), rows.len());
    /// assert_eq!(&pixels[..3], &[0, 1, 2]);
    /// assert_eq!(pixels[8], 20); // the first tile's second row
    /// assert!(rays.iter().zip(&pixels).all(|(r, &p)| *r == rows[p as usize]));
    /// ```
    pub fn tiled_rays(&self, width: u32, height: u32, tile: (u32, u32)) -> (Vec<Ray>, Vec<u32>) {
        let raster = self.raster(width, height);
        let (tw, th) = (tile.0.max(1), tile.1.max(1));
        let n = width as usize * height as usize;
        let (mut rays, mut pixels) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for ty in (0..height).step_by(th as usize) {
            for tx in (0..width).step_by(tw as usize) {
                for y in ty..(ty + th).min(height) {
                    for x in tx..(tx + tw).min(width) {
                        rays.push(raster.ray(x as f32 + 0.5, y as f32 + 0.5));
                        pixels.push(y * width + x);
                    }
                }
            }
        }
        (rays, pixels)
    }
}

/// A [`Camera`] set up for one image size (see [`Camera::raster`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Raster {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan: f32,
    aspect: f32,
    width: f32,
    height: f32,
}

impl Raster {
    /// The ray through the point `(x, y)` of the image, in pixels from its top left corner: the
    /// centre of pixel `(i, j)` is `(i + 0.5, j + 0.5)`, and any other point of the pixel gives
    /// a sub-pixel sample. The direction is unit length; the interval is `[0, inf]`.
    ///
    /// ```
    /// use rt_core::{Aabb, glam::Vec3};
    /// use rt_scene::Camera;
    /// let camera = Camera::framing(&Aabb::new(Vec3::ZERO, Vec3::ONE), 64, 48);
    /// let raster = camera.raster(64, 48);
    /// assert_eq!(raster.ray(3.5, 7.5), camera.primary_rays(64, 48)[7 * 64 + 3]);
    /// // The top left corner of the image looks up and to the left of its centre.
    /// let (corner, centre) = (raster.ray(0.0, 0.0), raster.ray(32.0, 24.0));
    /// assert!(corner.dir().y > centre.dir().y);
    /// ```
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = (2.0 * x / self.width - 1.0) * self.tan * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height) * self.tan;
        Ray::new(
            self.eye,
            (self.forward + sx * self.right + sy * self.up).normalize(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primary_rays_cover_the_image() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let cam = Camera::framing(&b, 8, 6);
        let rays = cam.primary_rays(8, 6);
        assert_eq!(rays.len(), 48);
        // The centre pixels look at (nearly) the box centre.
        let to_center = (b.center() - cam.eye).normalize();
        assert!(rays[3 * 8 + 4].dir().dot(to_center) > 0.99);
    }
}
