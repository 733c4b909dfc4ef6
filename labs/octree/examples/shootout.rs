//! Your octree traversal in the shootout, next to the built-in structures:
//! `cargo run --release --example shootout -- --scene teapot-in-stadium --structures lab-octree,octree,grid,bvh-binary`
//! takes every flag of `cargo xtask compare` (`--json`, `--out DIR`, `--grade lab-octree`, ...).

fn main() -> std::process::ExitCode {
    rt_shootout::Shootout::new()
        .with_triangles::<lab_octree::LabOctree>()
        .main()
}
