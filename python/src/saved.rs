//! A scene as bytes: `Scene.save`, `Scene.load` and pickling.
//!
//! The file is rt-persist's framing (magic, versions, section table, checksums) with four
//! sections: the structure's name, its preset and the parameters given by keyword (a line
//! each: the name, then the preset, then `key=value` lines), the scene's triangles in the order they were
//! added, the first triangle of each geometry, and the structure saved by its own
//! [`Persist`] (which checks itself on load). Loading rebuilds nothing.

use crate::params::Value;
use crate::scene::{Structure, with_structure};
use rt_bvh::Bvh;
use rt_core::{BruteForce, Triangle};
use rt_grid::Grid;
use rt_hgrid::HGrid;
use rt_kdtree::KdTree;
use rt_octree::Octree;
use rt_persist::{LoadError, Persist, Reader, Writer};

const KIND: &str = "rt-python::Scene";
const LAYOUT: u32 = 1;

/// What a saved scene holds.
#[derive(Debug)]
pub(crate) struct Saved {
    pub structure: String,
    pub preset: String,
    pub overrides: Vec<(String, Value)>,
    pub tris: Vec<Triangle>,
    pub offsets: Vec<u32>,
    pub built: Structure,
}

/// The bytes of a scene whose structure is built.
pub(crate) fn save(
    structure: &str,
    preset: &str,
    overrides: &[(String, Value)],
    tris: &[Triangle],
    offsets: &[u32],
    built: &Structure,
) -> Vec<u8> {
    let accel = with_structure!(built, a => a.save());
    let mut name = format!("{structure}\n{preset}");
    for (key, value) in overrides {
        name += &format!("\n{key}={}", value.text());
    }
    let name = name.into_bytes();
    let mut w = Writer::new::<Triangle>(KIND, LAYOUT);
    w.section_owned("name", name);
    w.section("tris", tris);
    w.section("offsets", offsets);
    w.section_owned("accel", accel);
    w.finish()
}

fn malformed(message: String) -> LoadError {
    LoadError::Malformed(message)
}

/// The scene saved in `bytes`, checked: the framing and checksum, the geometry table, every
/// triangle finite, and the structure by its own checks.
pub(crate) fn load(bytes: &[u8]) -> Result<Saved, LoadError> {
    let r = Reader::new::<Triangle>(bytes, KIND, LAYOUT)?;
    let name: Vec<u8> = r.section("name")?;
    let tris: Vec<Triangle> = r.section("tris")?;
    let offsets: Vec<u32> = r.section("offsets")?;
    let accel: Vec<u8> = r.section("accel")?;
    r.finish()?;
    let name = String::from_utf8(name).map_err(|_| malformed("the name is not UTF-8".into()))?;
    let mut lines = name.split('\n');
    let (Some(structure), Some(preset)) = (lines.next(), lines.next()) else {
        return Err(malformed(format!("no preset in the name {name:?}")));
    };
    let overrides = lines
        .map(|line| {
            let (key, value) = line
                .split_once('=')
                .ok_or_else(|| malformed(format!("a parameter line without '=': {line:?}")))?;
            Ok((key.to_owned(), Value::parse(value)))
        })
        .collect::<Result<Vec<_>, LoadError>>()?;
    if tris.is_empty() || tris.len() >= u32::MAX as usize {
        return Err(malformed(format!("{} triangles", tris.len())));
    }
    if let Some(i) = tris
        .iter()
        .position(|t| !(t.v0.is_finite() && t.v1.is_finite() && t.v2.is_finite()))
    {
        return Err(malformed(format!(
            "triangle {i} has a non-finite coordinate"
        )));
    }
    let increasing = offsets.windows(2).all(|w| w[0] < w[1]);
    if offsets.first() != Some(&0)
        || !increasing
        || offsets.last().is_some_and(|&o| o as usize >= tris.len())
    {
        return Err(malformed(format!(
            "the geometry table ({} entries) does not split {} triangles",
            offsets.len(),
            tris.len()
        )));
    }
    let built = match structure {
        "bvh" => Structure::Bvh(Bvh::load(&accel)?),
        "kdtree" => Structure::KdTree(KdTree::load(&accel)?),
        "grid" => Structure::Grid(Grid::load(&accel)?),
        "hgrid" => Structure::HGrid(HGrid::load(&accel)?),
        "octree" => Structure::Octree(Octree::load(&accel)?),
        "brute" => Structure::Brute(BruteForce::load(&accel)?),
        other => return Err(malformed(format!("unknown structure {other:?}"))),
    };
    Ok(Saved {
        structure: structure.to_owned(),
        preset: preset.to_owned(),
        overrides,
        tris,
        offsets,
        built,
    })
}
