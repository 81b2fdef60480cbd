#![no_main]
//! Format detection by content and extension, then the chosen reader: what `presrs inspect FILE` does.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&ext, rest)) = data.split_first() else {
        return;
    };
    let name = ["f.asf", "f.npy", "f.png", "f.txt", "f.csv", "f"][usize::from(ext) % 6];
    let dir = std::env::temp_dir().join(format!("presrs-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(name);
    if std::fs::write(&path, rest).is_ok() {
        let _ = presrs_io::read_recording_with(&path, &presrs_io::ReadOptions::lenient());
    }
});
