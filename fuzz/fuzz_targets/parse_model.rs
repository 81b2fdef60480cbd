#![no_main]
//! Model-file loader; a model that loads must also classify frames without panicking (a corrupted but
//! well-formed file must be rejected at load time, not crash later).
use libfuzzer_sys::fuzz_target;
use presrs_core::{Frame, Grid};

fuzz_target!(|data: &[u8]| {
    let Ok(file) = presrs_io::model_file::parse_model(data, "fuzz.json") else {
        return;
    };
    let mut session = file.model.session();
    for grid in [file.model.image_grid(), Grid::new(44, 44)] {
        if grid.len() > 1 << 16 {
            continue;
        }
        let values: Vec<f64> = (0..grid.len()).map(|i| (i % 17) as f64).collect();
        if let Ok(frame) = Frame::new(grid, values) {
            let _ = session.classify(&frame.view());
        }
    }
});
