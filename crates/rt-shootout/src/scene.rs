//! Scenes by name: what every command's `--scene` takes.

use rt_core::Triangle;
use rt_scene::scenes::{self, BUILTIN_SCENES};
use std::path::Path;

/// The triangles of a built-in scene or a scene file (OBJ, PLY, glTF), or a one-line error.
pub fn load_scene(spec: &str) -> Result<(String, Vec<Triangle>), String> {
    if let Some((scene, size)) = scenes::resolve(spec)? {
        return Ok((spec.to_string(), scene.make(size).triangles()));
    }
    let path = Path::new(spec);
    if !path.exists() && !spec.contains(['/', '\\', '.']) {
        let names: Vec<&str> = BUILTIN_SCENES.iter().map(|s| s.name).collect();
        return Err(format!(
            "no built-in scene or file named `{spec}` (built-in scenes: {}; any of them with a \
             size, such as `random-soup:1M`)",
            names.join(", ")
        ));
    }
    let mesh = rt_scene::load_mesh(path).map_err(|e| e.to_string())?;
    Ok((spec.to_string(), mesh.triangles()))
}
