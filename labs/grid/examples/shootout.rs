//! Your grid in the shootout, next to the built-in structures:
//! `cargo run --release --example shootout -- --scene teapot-in-stadium --structures lab-grid,grid,bvh`
//! takes every flag of `cargo xtask compare` (`--json`, `--out DIR`, `--grade lab-grid`, ...).

fn main() -> std::process::ExitCode {
    rt_shootout::Shootout::new()
        .with_triangles::<lab_grid::LabGrid>()
        .main()
}
