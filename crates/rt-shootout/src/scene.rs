//! Scenes by name: what every command's `--scene` takes.

use rt_core::Triangle;
use rt_scene::scenes::{self, BUILTIN_SCENES};
use std::path::Path;

/// The prefix that names one of the conformance kit's scenes: `kit:identical_triangles`.
pub const KIT_PREFIX: &str = "kit:";

/// The conformance kit's scene that `spec` names (`kit:NAME`, NAME one of
/// [`rt_conformance::SCENES`]): its triangles and its rays; `Ok(None)` for any other spec.
///
/// # Errors
/// One line for a `kit:` name the kit does not have.
pub fn kit_scene(spec: &str) -> Result<Option<rt_conformance::Scene>, String> {
    let Some(name) = spec.strip_prefix(KIT_PREFIX) else {
        return Ok(None);
    };
    if !rt_conformance::SCENES.contains(&name) {
        return Err(format!(
            "no conformance kit scene named `{name}` (the kit's scenes: {})",
            rt_conformance::SCENES.join(", ")
        ));
    }
    Ok(Some(rt_conformance::scene(name)))
}

/// The triangles of a built-in scene, a conformance kit scene (`kit:NAME`) or a scene file
/// (OBJ, PLY, glTF), or a one-line error.
pub fn load_scene(spec: &str) -> Result<(String, Vec<Triangle>), String> {
    if let Some(kit) = kit_scene(spec)? {
        return Ok((spec.to_string(), kit.triangles));
    }
    if let Some((scene, size)) = scenes::resolve(spec)? {
        return Ok((spec.to_string(), scene.make(size).triangles()));
    }
    let path = Path::new(spec);
    if !path.exists() && !spec.contains(['/', '\\', '.']) {
        let names: Vec<&str> = BUILTIN_SCENES.iter().map(|s| s.name).collect();
        return Err(format!(
            "no built-in scene or file named `{spec}` (built-in scenes: {}; any of them with a \
             size, such as `random-soup:1M`; or a conformance kit scene, such as \
             `kit:identical_triangles`)",
            names.join(", ")
        ));
    }
    let mesh = rt_scene::load_mesh(path).map_err(|e| e.to_string())?;
    Ok((spec.to_string(), mesh.triangles()))
}
