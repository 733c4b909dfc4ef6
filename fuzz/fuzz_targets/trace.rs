//! A small triangle soup and rays (see `rt_shootout::fuzz::decode`): every structure builds,
//! validates and answers exactly as brute force does.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(e) = rt_shootout::fuzz::trace(data) {
        panic!("{e}");
    }
});
