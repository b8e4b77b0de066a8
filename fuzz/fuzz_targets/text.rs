//! The text reader (CSV, tab, semicolon and whitespace separated, UTF-8 or UTF-16) on any
//! bytes: the first byte picks the delimiter, header and row options, the rest is the file.
#![no_main]

use std::path::Path;

use hystcomp_fuzz::{ensure, io_properties::check_record};
use hystcomp_io::data::{Column, Delimiter, Header, ReadOptions, read_bytes};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&selector, file)) = data.split_first() else {
        return;
    };
    let options = ReadOptions {
        delimiter: [
            Delimiter::Auto,
            Delimiter::Comma,
            Delimiter::Tab,
            Delimiter::Semicolon,
            Delimiter::Whitespace,
        ][usize::from(selector % 5)],
        header: [Header::Auto, Header::Present, Header::Absent][usize::from(selector / 5 % 3)],
        rows: (selector >= 128).then_some(hystcomp_io::data::RowRange {
            first: 2,
            last: Some(5),
        }),
    };
    for columns in [
        vec![Column::Index(1)],
        vec![Column::Index(2), Column::Index(1)],
        vec![Column::Name("u".into()), Column::Index(3)],
    ] {
        let result = read_bytes(Path::new("fuzz.csv"), file, &columns, &options);
        ensure(check_record(&result, "fuzz.csv", columns.len()));
    }
});
