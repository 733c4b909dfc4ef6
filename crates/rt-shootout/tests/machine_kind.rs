//! The machine kinds the results pages are kept by.

use rt_shootout::measure::machine_kind_of;

#[test]
fn machine_kinds_tell_the_zen_generations_and_xeons_apart() {
    let slug = |v: &str, f: u32, m: u32| machine_kind_of(v, f, m).slug;
    // Zen 4 (Genoa: family 25, model 17) and Zen 5 (Turin: family 26, model 2) apart,
    // and Zen 3 (Milan: family 25, model 1) apart from Zen 4.
    assert_eq!(slug("AuthenticAMD", 25, 0x11), "amd-zen4");
    assert_eq!(slug("AuthenticAMD", 25, 0x01), "amd-zen3");
    assert_eq!(slug("AuthenticAMD", 26, 0x02), "amd-zen5");
    assert_eq!(slug("AuthenticAMD", 23, 0x31), "amd-zen2");
    assert_eq!(slug("GenuineIntel", 6, 207), "intel-emerald-rapids");
    assert_eq!(slug("GenuineIntel", 6, 143), "intel-sapphire-rapids");
    // Unknown models keep their numbers, in a file name's characters.
    assert_eq!(slug("GenuineIntel", 6, 999), "intel-family6-model999");
    assert_eq!(slug("Hygon Genuine", 24, 1), "hygongenuine-family24-model1");
    let k = machine_kind_of("AuthenticAMD", 25, 0x11);
    assert_eq!(k.name, "AMD Zen 4 (family 25, model 17)");
}
