//! The shootout with one more structure: what a student's crate puts in `examples/shootout.rs`.
//!
//! ```sh
//! cargo run --release -p rt-shootout --example groups -- --scene teapot-in-stadium --structures groups,bvh,grid
//! ```
//!
//! Every flag of `cargo xtask compare` works (`--json`, `--rays-file`, `--out DIR`, ...).

mod groups;

fn main() -> std::process::ExitCode {
    rt_shootout::Shootout::new()
        .with_triangles::<groups::Groups>()
        .main()
}
