//! A tiny writer of MATLAB Level-5 MAT-files, following MathWorks' "MAT-File Format": a
//! 128-byte header, then one miMATRIX data element per variable (array flags, dimensions,
//! name, real part, imaginary part if complex), each sub-element padded to 8 bytes; or each
//! variable wrapped in an miCOMPRESSED element holding a zlib stream (stored blocks).
#![allow(dead_code)]
const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MX_DOUBLE_CLASS: u32 = 6;
const MX_SINGLE_CLASS: u32 = 7;
const MX_INT8_CLASS: u32 = 8;
const MX_INT16_CLASS: u32 = 10;
const MX_INT32_CLASS: u32 = 12;
const MX_UINT64_CLASS: u32 = 15;
const COMPLEX_FLAG: u32 = 0x0800;

pub enum Values<'a> {
    Double(&'a [f64]),
    /// A double array whose values fit in 8 bits, stored compactly as MATLAB does.
    DoubleAsUInt8(&'a [u8]),
    /// A double array whose values fit in 16 bits, stored compactly as MATLAB does.
    DoubleAsInt16(&'a [i16]),
    Int16(&'a [i16]),
    Int32(&'a [i32]),
    Int8(&'a [i8]),
    Single(&'a [f32]),
    UInt64(&'a [u64]),
    Complex(&'a [f64], &'a [f64]),
}

pub struct Variable<'a> {
    pub name: &'a str,
    /// Dimensions as written (negative ones too, for damaged files).
    pub dims: &'a [i64],
    pub values: Values<'a>,
}

pub fn var<'a>(name: &'a str, dims: &'a [i64], values: &'a [f64]) -> Variable<'a> {
    Variable {
        name,
        dims,
        values: Values::Double(values),
    }
}

struct Out {
    bytes: Vec<u8>,
    big_endian: bool,
}

impl Out {
    fn u16(&mut self, v: u16) {
        let b = if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.bytes.extend_from_slice(&b);
    }
    fn u32(&mut self, v: u32) {
        let b = if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.bytes.extend_from_slice(&b);
    }
    fn i16(&mut self, v: i16) {
        let b = if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.bytes.extend_from_slice(&b);
    }
    fn i32(&mut self, v: i32) {
        let b = if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.bytes.extend_from_slice(&b);
    }
    fn u64(&mut self, v: u64) {
        let b = if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.bytes.extend_from_slice(&b);
    }
    fn f64(&mut self, v: f64) {
        let b = if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        self.bytes.extend_from_slice(&b);
    }
    fn pad8(&mut self) {
        while !self.bytes.len().is_multiple_of(8) {
            self.bytes.push(0);
        }
    }
    /// A data element: tag (type, byte count), the data, padding to 8 bytes.
    fn element(&mut self, data_type: u32, write: impl FnOnce(&mut Out)) {
        let mut body = Out {
            bytes: Vec::new(),
            big_endian: self.big_endian,
        };
        write(&mut body);
        self.u32(data_type);
        self.u32(u32::try_from(body.bytes.len()).expect("a small element"));
        self.bytes.extend_from_slice(&body.bytes);
        self.pad8();
    }
}

fn matrix(out: &mut Out, v: &Variable) {
    out.element(MI_MATRIX, |m| {
        let (class, flags) = match v.values {
            Values::Double(_) | Values::DoubleAsUInt8(_) | Values::DoubleAsInt16(_) => {
                (MX_DOUBLE_CLASS, 0)
            }
            Values::Int16(_) => (MX_INT16_CLASS, 0),
            Values::Int32(_) => (MX_INT32_CLASS, 0),
            Values::Int8(_) => (MX_INT8_CLASS, 0),
            Values::Single(_) => (MX_SINGLE_CLASS, 0),
            Values::UInt64(_) => (MX_UINT64_CLASS, 0),
            Values::Complex(..) => (MX_DOUBLE_CLASS, COMPLEX_FLAG),
        };
        m.element(MI_UINT32, |e| {
            e.u32(class | flags);
            e.u32(0);
        });
        m.element(MI_INT32, |e| {
            for &d in v.dims {
                e.i32(i32::try_from(d).expect("a small dimension"));
            }
        });
        m.element(MI_INT8, |e| e.bytes.extend_from_slice(v.name.as_bytes()));
        match v.values {
            Values::Double(values) => {
                m.element(MI_DOUBLE, |e| values.iter().for_each(|&x| e.f64(x)))
            }
            Values::DoubleAsUInt8(values) => {
                m.element(MI_UINT8, |e| e.bytes.extend_from_slice(values))
            }
            Values::DoubleAsInt16(values) | Values::Int16(values) => {
                m.element(MI_INT16, |e| values.iter().for_each(|&x| e.i16(x)))
            }
            Values::Int32(values) => m.element(MI_INT32, |e| values.iter().for_each(|&x| e.i32(x))),
            Values::Int8(values) => m.element(MI_INT8, |e| {
                values
                    .iter()
                    .for_each(|&x| e.bytes.push(x.to_ne_bytes()[0]))
            }),
            Values::Single(values) => m.element(MI_SINGLE, |e| {
                values.iter().for_each(|&x| e.u32(x.to_bits()))
            }),
            Values::UInt64(values) => {
                m.element(MI_UINT64, |e| values.iter().for_each(|&x| e.u64(x)))
            }
            Values::Complex(re, im) => {
                m.element(MI_DOUBLE, |e| re.iter().for_each(|&x| e.f64(x)));
                m.element(MI_DOUBLE, |e| im.iter().for_each(|&x| e.f64(x)));
            }
        }
    });
}

/// A zlib stream of stored (uncompressed) deflate blocks, per RFC 1950 and 1951.
fn zlib_stored(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01];
    let chunks: Vec<&[u8]> = if data.is_empty() {
        vec![&[]]
    } else {
        data.chunks(65_535).collect()
    };
    for (i, chunk) in chunks.iter().enumerate() {
        out.push(u8::from(i + 1 == chunks.len()));
        let len = u16::try_from(chunk.len()).expect("a stored block");
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(chunk);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &byte in data {
        a = (a + u32::from(byte)) % 65_521;
        b = (b + a) % 65_521;
    }
    out.extend_from_slice(&((b << 16) | a).to_be_bytes());
    out
}

/// The 128-byte header: text, subsystem offset, version 0x0100, endian indicator.
fn header(out: &mut Out, text: &str, version: u16) {
    let mut line = text.as_bytes().to_vec();
    line.resize(116, b' ');
    out.bytes.extend_from_slice(&line);
    out.bytes.extend_from_slice(&[0; 8]);
    out.u16(version);
    // The characters 'M' and 'I' written as one 16-bit number: "IM" on a little-endian
    // machine, "MI" on a big-endian one.
    out.u16(u16::from_be_bytes(*b"MI"));
}

pub fn file(variables: &[Variable], big_endian: bool, compressed: bool) -> Vec<u8> {
    let mut out = Out {
        bytes: Vec::new(),
        big_endian,
    };
    header(
        &mut out,
        "MATLAB 5.0 MAT-file, Platform: hystcomp tests, Created on: Mon Jan  1 00:00:00 2024",
        0x0100,
    );
    for v in variables {
        if compressed {
            let mut inner = Out {
                bytes: Vec::new(),
                big_endian,
            };
            matrix(&mut inner, v);
            let stream = zlib_stored(&inner.bytes);
            out.u32(MI_COMPRESSED);
            out.u32(u32::try_from(stream.len()).expect("a small stream"));
            out.bytes.extend_from_slice(&stream);
        } else {
            matrix(&mut out, v);
        }
    }
    out.bytes
}

/// The start of a v7.3 file: its header text and version 0x0200, then the HDF5
/// signature at offset 512.
pub fn v73_stub() -> Vec<u8> {
    let mut out = Out {
        bytes: Vec::new(),
        big_endian: false,
    };
    header(
        &mut out,
        "MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 .",
        0x0200,
    );
    out.bytes.resize(512, 0);
    out.bytes.extend_from_slice(b"\x89HDF\r\n\x1a\n");
    out.bytes.resize(1024, 0);
    out.bytes
}
