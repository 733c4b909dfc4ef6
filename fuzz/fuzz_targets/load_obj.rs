//! Bytes to a mesh or an error with the Obj loader: no panic, and a sound mesh if any.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    rt_shootout::fuzz::load(rt_scene::SceneFormat::Obj, data);
});
