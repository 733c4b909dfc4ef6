//! The trace target's cases (see `rt_shootout::fuzz::decode`): every structure's bundle queries
//! answer each ray exactly as its single-ray queries do, in every order and bundle size.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(e) = rt_shootout::fuzz::bundle(data) {
        panic!("{e}");
    }
});
