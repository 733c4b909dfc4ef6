//! Your hierarchical grid walk in the shootout, next to the built-in structures:
//! `cargo run --release --example shootout -- --scene teapot-in-stadium --structures lab-hgrid,hgrid,grid,octree`
//! takes every flag of `cargo xtask compare` (`--json`, `--out DIR`, `--grade lab-hgrid`, ...).

fn main() -> std::process::ExitCode {
    rt_shootout::Shootout::new()
        .with_triangles::<lab_hgrid::LabHGrid>()
        .main()
}
