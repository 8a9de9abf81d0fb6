//! The TOML config: any text goes through the same parse and validation as `bearingd run
//! --config` and `bearingd validate`.
#![no_main]

use bearingd_fuzz::{default_budget, with_budget};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    with_budget(default_budget(data.len()), || {
        if let Err(e) = bearingd::config::parse(text, "fuzz") {
            let _ = e.to_string();
        }
    });
});
