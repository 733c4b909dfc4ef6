//! Bytes as a saved `rt-hgrid` structure (see `rt_shootout::fuzz::saved`): loading refuses them
//! or gives a structure that answers, and whose own file loads to the same answers.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(e) = rt_shootout::fuzz::saved("saved_hgrid", data) {
        panic!("{e}");
    }
});
