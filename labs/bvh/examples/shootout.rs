//! Your BVH in the shootout, next to the built-in structures:
//! `cargo run --release --example shootout -- --scene teapot-in-stadium --structures lab-bvh,lab-bvh-sah,bvh-median,bvh-binary,kdtree`
//! takes every flag of `cargo xtask compare` (`--json`, `--out DIR`, `--grade lab-bvh-sah`, ...).

fn main() -> std::process::ExitCode {
    rt_shootout::Shootout::new()
        .with_triangles::<lab_bvh::LabBvh>()
        .main()
}
