//! The MATLAB Level-5 reader on any bytes (the seed corpus holds valid files, little and big
//! endian, compressed or not): variables by name, `name:k` columns and the only variable.
#![no_main]

use std::path::Path;

use hystcomp_fuzz::{ensure, io_properties::check_record};
use hystcomp_io::data::{Column, ReadOptions, read_bytes};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for columns in [
        vec![Column::Name("t".into()), Column::Name("u".into())],
        vec![Column::Name("data:2".into())],
        vec![Column::Index(1)],
        vec![Column::Name("counts".into())],
    ] {
        let result = read_bytes(
            Path::new("fuzz.mat"),
            data,
            &columns,
            &ReadOptions::default(),
        );
        ensure(check_record(&result, "fuzz.mat", columns.len()));
    }
});
