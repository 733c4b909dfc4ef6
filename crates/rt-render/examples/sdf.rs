//! The signed distance field of a mesh on a grid, written as a NumPy `.npy` file, and a slice of
//! it drawn as a PNG.
//!
//! ```sh
//! cargo run --release -p rt-render --example sdf -- ../shared/meshes/stanford-bunny.obj
//! cargo run --release -p rt-render --example sdf -- MESH --resolution 64 --out field.npy --slice slice.png
//! ```
//!
//! The grid has `resolution` samples along the longest side of the mesh's box grown by a tenth
//! on every side, and as many along the others as keep the samples `spacing` apart; sample
//! `(i, j, k)` is at `origin + spacing · (i, j, k)`, and the file holds a `float32` array of shape
//! `(nz, ny, nx)` (`numpy.load` reads it), negative inside. The program prints the origin and
//! the spacing.
//!
//! Each sample is the BVH's closest-point distance, signed by the fast winding number
//! ([`rt_sdf::WindingTree`]), so meshes with holes get a sensible inside. The slice is the plane
//! through the box's centre facing `z` (for the bunny, the view from the front), drawn at 512
//! pixels across: blue inside, orange outside, darker bands every 2% of the box's diagonal and
//! the surface itself in black.

use rayon::prelude::*;
use rt_bvh::Bvh;
use rt_core::{Accel, glam::Vec3};
use rt_render::Image;
use rt_sdf::{SignedDistance, WindingTree};
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

struct Options {
    mesh: PathBuf,
    resolution: usize,
    out: PathBuf,
    slice: PathBuf,
}

fn options() -> Result<Options, String> {
    let mut args = std::env::args().skip(1);
    let mut o = Options {
        mesh: PathBuf::new(),
        resolution: 128,
        out: PathBuf::from("sdf.npy"),
        slice: PathBuf::from("sdf-slice.png"),
    };
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--resolution" => {
                let v = value()?;
                o.resolution = v
                    .parse()
                    .ok()
                    .filter(|&r| (2..=1024).contains(&r))
                    .ok_or(format!("--resolution must be 2 to 1024, not {v}"))?;
            }
            "--out" => o.out = value()?.into(),
            "--slice" => o.slice = value()?.into(),
            _ if a.starts_with('-') => return Err(format!("unknown option {a}")),
            _ => o.mesh = a.into(),
        }
    }
    if o.mesh.as_os_str().is_empty() {
        return Err("usage: sdf MESH [--resolution N] [--out FILE.npy] [--slice FILE.png]".into());
    }
    Ok(o)
}

/// The `.npy` (version 1.0) file of a `float32` array of shape `(nz, ny, nx)`.
fn npy(values: &[f32], [nx, ny, nz]: [usize; 3]) -> Vec<u8> {
    let mut header =
        format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({nz}, {ny}, {nx}), }}");
    // The magic, the version and the length take 10 bytes; the header ends in a newline and
    // pads the data's start to a multiple of 64.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    for v in values {
        bytes.extend(v.to_le_bytes());
    }
    bytes
}

/// The colour of signed distance `d` where bands are `band` wide.
fn colour(d: f32, band: f32, surface: f32) -> [u8; 3] {
    if d.abs() < surface {
        return [0, 0, 0];
    }
    let base = if d < 0.0 {
        [70.0, 120.0, 200.0]
    } else {
        [235.0, 150.0, 70.0]
    };
    // Lighter away from the surface, with a darker line at every band.
    let t = (d.abs() / (8.0 * band)).min(1.0);
    let line = if (d.abs() / band).fract() < 0.08 {
        0.75
    } else {
        1.0
    };
    base.map(|c: f32| ((c + (255.0 - c) * 0.6 * t) * line) as u8)
}

fn main() {
    let o = match options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let mesh = match rt_scene::load_mesh(&o.mesh) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let tris = mesh.triangles();
    let t = Instant::now();
    let bvh = Bvh::build(&tris, &Default::default());
    let sign = WindingTree::build(&tris).expect("a mesh holds triangles only");
    let built = t.elapsed();
    let bounds = bvh.bounds();
    if bounds.is_empty() {
        eprintln!("error: {}: no valid triangles", o.mesh.display());
        std::process::exit(1);
    }
    let margin = bounds.extent() * 0.1;
    let (lo, size) = (bounds.min - margin, bounds.extent() + 2.0 * margin);
    let spacing = size.max_element() / (o.resolution - 1) as f32;
    let n = (size / spacing).ceil().as_uvec3() + 1;
    let (nx, ny, nz) = (n.x as usize, n.y as usize, n.z as usize);

    let t = Instant::now();
    let mut values = vec![0.0f32; nx * ny * nz];
    values
        .par_chunks_mut(nx)
        .enumerate()
        .for_each(|(row, out)| {
            let (j, k) = (row % ny, row / ny);
            for (i, v) in out.iter_mut().enumerate() {
                let p = lo + spacing * Vec3::new(i as f32, j as f32, k as f32);
                *v = bvh
                    .signed_distance(&sign, p, f32::INFINITY)
                    .map_or(f32::INFINITY, |s| s.distance);
            }
        });
    let field = t.elapsed();
    let inside = values.iter().filter(|v| **v < 0.0).count();
    if let Err(e) =
        std::fs::File::create(&o.out).and_then(|mut f| f.write_all(&npy(&values, [nx, ny, nz])))
    {
        eprintln!("error: {}: cannot write: {e}", o.out.display());
        std::process::exit(1);
    }
    println!(
        "{}: {} triangles; BVH and winding tree built in {:.0} ms",
        o.mesh.display(),
        tris.len(),
        built.as_secs_f64() * 1e3
    );
    println!(
        "{nx}×{ny}×{nz} samples in {:.2} s on {} threads ({:.2} µs per sample), {:.1}% inside",
        field.as_secs_f64(),
        rayon::current_num_threads(),
        field.as_secs_f64() * 1e6 * rayon::current_num_threads() as f64 / values.len() as f64,
        100.0 * inside as f64 / values.len() as f64
    );
    println!(
        "wrote {} (origin {:?}, spacing {spacing})",
        o.out.display(),
        lo.to_array()
    );

    // The slice: 512 pixels across the box's wider side in x and y, through its centre in z.
    let width = 512u32;
    let step = size.x.max(size.y) / width as f32;
    let height = ((size.y / step).ceil() as u32).max(1);
    let z = lo.z + 0.5 * size.z;
    let band = 0.02 * size.length();
    let rows: Vec<Vec<[u8; 3]>> = (0..height)
        .into_par_iter()
        .map(|y| {
            (0..width)
                .map(|x| {
                    let p = Vec3::new(
                        lo.x + (x as f32 + 0.5) * step,
                        lo.y + size.y - (y as f32 + 0.5) * step,
                        z,
                    );
                    let d = bvh
                        .signed_distance(&sign, p, f32::INFINITY)
                        .map_or(f32::INFINITY, |s| s.distance);
                    colour(d, band, 0.75 * step)
                })
                .collect()
        })
        .collect();
    let mut image = match Image::new(width, height) {
        Ok(i) => i,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    image.pixels = rows.concat();
    if let Err(e) = image.save_png(&o.slice) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
    println!("wrote {} (the plane z = {z})", o.slice.display());
}
