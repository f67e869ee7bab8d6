//! The PLY number types ([`PlyScalar`]) and encodings ([`PlyEncoding`]): their names, sizes and
//! ranges, and one value's binary and ascii forms, read and written exactly.

use std::io::{self, Write};

use crate::io::write_f64;

/// How a PLY file encodes its elements.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyEncoding {
    /// `format ascii 1.0`.
    Ascii,
    /// `format binary_little_endian 1.0`.
    BinaryLittleEndian,
    /// `format binary_big_endian 1.0`.
    BinaryBigEndian,
}

impl PlyEncoding {
    /// The word after `format` in the header.
    pub fn keyword(self) -> &'static str {
        match self {
            Self::Ascii => "ascii",
            Self::BinaryLittleEndian => "binary_little_endian",
            Self::BinaryBigEndian => "binary_big_endian",
        }
    }
}

/// A PLY number type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlyScalar {
    /// `char` or `int8`.
    Char,
    /// `uchar` or `uint8`.
    UChar,
    /// `short` or `int16`.
    Short,
    /// `ushort` or `uint16`.
    UShort,
    /// `int` or `int32`.
    Int,
    /// `uint` or `uint32`.
    UInt,
    /// `float` or `float32`.
    Float,
    /// `double` or `float64`.
    Double,
}

pub(super) const TYPE_NAMES: &str = "char, uchar, short, ushort, int, uint, float, double, int8, uint8, int16, uint16, int32, uint32, float32 or float64";

impl PlyScalar {
    /// Every type, smallest first.
    pub const ALL: [PlyScalar; 8] =
        [Self::Char, Self::UChar, Self::Short, Self::UShort, Self::Int, Self::UInt, Self::Float, Self::Double];

    /// The type a header names (`uchar` or `uint8`, …).
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::Char,
            "uchar" | "uint8" => Self::UChar,
            "short" | "int16" => Self::Short,
            "ushort" | "uint16" => Self::UShort,
            "int" | "int32" => Self::Int,
            "uint" | "uint32" => Self::UInt,
            "float" | "float32" => Self::Float,
            "double" | "float64" => Self::Double,
            _ => return None,
        })
    }

    /// The type's classic name (`uchar`, `float`, …).
    pub fn name(self) -> &'static str {
        match self {
            Self::Char => "char",
            Self::UChar => "uchar",
            Self::Short => "short",
            Self::UShort => "ushort",
            Self::Int => "int",
            Self::UInt => "uint",
            Self::Float => "float",
            Self::Double => "double",
        }
    }

    /// Bytes per value in a binary file.
    pub fn size(self) -> usize {
        match self {
            Self::Char | Self::UChar => 1,
            Self::Short | Self::UShort => 2,
            Self::Int | Self::UInt | Self::Float => 4,
            Self::Double => 8,
        }
    }

    /// Whether it is one of the integer types.
    pub fn is_integer(self) -> bool {
        !matches!(self, Self::Float | Self::Double)
    }

    /// The smallest and largest value of an integer type (of `f64` for the float types).
    pub(super) fn range(self) -> (f64, f64) {
        match self {
            Self::Char => (i8::MIN.into(), i8::MAX.into()),
            Self::UChar => (0.0, u8::MAX.into()),
            Self::Short => (i16::MIN.into(), i16::MAX.into()),
            Self::UShort => (0.0, u16::MAX.into()),
            Self::Int => (i32::MIN.into(), i32::MAX.into()),
            Self::UInt => (0.0, u32::MAX.into()),
            Self::Float | Self::Double => (f64::MIN, f64::MAX),
        }
    }

    /// `v` as this type holds it: rounded to the nearest integer and clamped to the type's
    /// range (NaN: 0) for the integer types, rounded to `f32` for `float`, as is for `double`.
    pub fn coerce(self, v: f64) -> f64 {
        match self {
            Self::Float => f64::from(v as f32),
            Self::Double => v,
            _ if v.is_nan() => 0.0,
            _ => {
                let (lo, hi) = self.range();
                // `+ 0.0` turns −0 into 0, which is what an integer holds.
                v.round().clamp(lo, hi) + 0.0
            }
        }
    }

    /// Decodes `bytes` (exactly [`Self::size`] long; shorter slices are zero-padded). Every PLY
    /// type converts to `f64` exactly.
    pub(super) fn decode(self, bytes: &[u8], big_endian: bool) -> f64 {
        fn take<const N: usize>(bytes: &[u8], big_endian: bool) -> [u8; N] {
            let mut out = [0; N];
            for (o, b) in out.iter_mut().zip(bytes) {
                *o = *b;
            }
            // Normalise to little endian so one `from_le_bytes` serves both.
            if big_endian {
                out.reverse();
            }
            out
        }
        match self {
            Self::Char => f64::from(i8::from_le_bytes(take(bytes, big_endian))),
            Self::UChar => f64::from(u8::from_le_bytes(take(bytes, big_endian))),
            Self::Short => f64::from(i16::from_le_bytes(take(bytes, big_endian))),
            Self::UShort => f64::from(u16::from_le_bytes(take(bytes, big_endian))),
            Self::Int => f64::from(i32::from_le_bytes(take(bytes, big_endian))),
            Self::UInt => f64::from(u32::from_le_bytes(take(bytes, big_endian))),
            Self::Float => f64::from(f32::from_le_bytes(take(bytes, big_endian))),
            Self::Double => f64::from_le_bytes(take(bytes, big_endian)),
        }
    }

    /// Appends `v`, [coerced](Self::coerce) to this type, in binary.
    pub(super) fn encode(self, v: f64, big_endian: bool, out: &mut Vec<u8>) {
        fn order<const N: usize>(mut le: [u8; N], big_endian: bool) -> [u8; N] {
            if big_endian {
                le.reverse();
            }
            le
        }
        let v = self.coerce(v);
        // The casts are exact: `v` is an integer within the type's range, or an f32 value.
        match self {
            Self::Char => out.extend_from_slice(&order((v as i8).to_le_bytes(), big_endian)),
            Self::UChar => out.extend_from_slice(&order((v as u8).to_le_bytes(), big_endian)),
            Self::Short => out.extend_from_slice(&order((v as i16).to_le_bytes(), big_endian)),
            Self::UShort => out.extend_from_slice(&order((v as u16).to_le_bytes(), big_endian)),
            Self::Int => out.extend_from_slice(&order((v as i32).to_le_bytes(), big_endian)),
            Self::UInt => out.extend_from_slice(&order((v as u32).to_le_bytes(), big_endian)),
            Self::Float => out.extend_from_slice(&order((v as f32).to_le_bytes(), big_endian)),
            Self::Double => out.extend_from_slice(&order(v.to_le_bytes(), big_endian)),
        }
    }

    /// Appends `v`, [coerced](Self::coerce) to this type, as ascii: integers as integers,
    /// `float` as the shortest text that reads back as the same `f32`, `double` likewise.
    pub(super) fn write_ascii(self, v: f64, out: &mut Vec<u8>) -> io::Result<()> {
        let v = self.coerce(v);
        match self {
            Self::Float => write!(out, "{:?}", v as f32),
            Self::Double => write_f64(out, v),
            _ => write!(out, "{}", v as i64),
        }
    }

    /// The value an ascii token stands for, as this type holds it; `None` if it is not a
    /// number, or for an integer type not an integer in its range.
    pub(super) fn parse_ascii(self, token: &str) -> Option<f64> {
        match self {
            // Parsed as f32 directly: rounding through f64 first could round twice.
            Self::Float => token.parse::<f32>().ok().map(f64::from),
            Self::Double => token.parse::<f64>().ok(),
            _ => {
                let v = token.parse::<i64>().map(|i| i as f64).or_else(|_| token.parse::<f64>()).ok()?;
                let (lo, hi) = self.range();
                (v.fract() == 0.0 && v >= lo && v <= hi).then_some(v + 0.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn decodes_every_type_in_both_endians() {
        assert_eq!(PlyScalar::Char.decode(&[0xff], false), -1.0);
        assert_eq!(PlyScalar::UChar.decode(&[0xff], true), 255.0);
        assert_eq!(PlyScalar::Short.decode(&[0xfe, 0xff], false), -2.0);
        assert_eq!(PlyScalar::Short.decode(&[0xff, 0xfe], true), -2.0);
        assert_eq!(PlyScalar::UShort.decode(&[0x01, 0x02], true), 258.0);
        assert_eq!(PlyScalar::Int.decode(&(-7i32).to_be_bytes(), true), -7.0);
        assert_eq!(PlyScalar::UInt.decode(&u32::MAX.to_le_bytes(), false), f64::from(u32::MAX));
        assert_eq!(PlyScalar::Float.decode(&1.5f32.to_be_bytes(), true), 1.5);
        assert_eq!(PlyScalar::Double.decode(&0.1f64.to_le_bytes(), false), 0.1);
        for (name, ty) in [
            ("float32", PlyScalar::Float),
            ("uint8", PlyScalar::UChar),
            ("int", PlyScalar::Int),
            ("double", PlyScalar::Double),
        ] {
            assert_eq!(PlyScalar::parse(name), Some(ty));
        }
        assert_eq!(PlyScalar::parse("float16"), None);
    }

    #[test]
    fn encode_then_decode_is_exact_at_the_ends_of_every_range() {
        for ty in PlyScalar::ALL {
            let (lo, hi) = ty.range();
            let samples = match ty {
                PlyScalar::Float => vec![f64::from(f32::MIN), f64::from(f32::MIN_POSITIVE), 0.1f32.into(), -0.0],
                PlyScalar::Double => vec![f64::MIN, 5e-324, 0.1, -0.0],
                _ => vec![lo, hi, 0.0, (lo + hi).div_euclid(2.0)],
            };
            for v in samples {
                for big in [false, true] {
                    let mut bytes = Vec::new();
                    ty.encode(v, big, &mut bytes);
                    assert_eq!(bytes.len(), ty.size());
                    assert_eq!(ty.decode(&bytes, big).to_bits(), v.to_bits(), "{ty:?} {v} big {big}");
                }
                let mut text = Vec::new();
                ty.write_ascii(v, &mut text).unwrap();
                let text = String::from_utf8(text).unwrap();
                assert_eq!(ty.parse_ascii(&text).map(f64::to_bits), Some(v.to_bits()), "{ty:?} {text}");
            }
        }
    }

    #[test]
    fn ascii_values_are_read_as_their_type_holds_them() {
        assert_eq!(PlyScalar::Float.parse_ascii("0.1"), Some(f64::from(0.1f32)));
        assert_eq!(PlyScalar::Double.parse_ascii("0.1"), Some(0.1));
        assert_eq!(PlyScalar::UChar.parse_ascii("255.0"), Some(255.0));
        assert_eq!(PlyScalar::UChar.parse_ascii("256"), None);
        assert_eq!(PlyScalar::UChar.parse_ascii("-1"), None);
        assert_eq!(PlyScalar::Int.parse_ascii("1.5"), None);
        assert_eq!(PlyScalar::Char.parse_ascii("-0").map(f64::to_bits), Some(0f64.to_bits()));
        assert_eq!(PlyScalar::Short.coerce(1e9), f64::from(i16::MAX));
        assert_eq!(PlyScalar::UInt.coerce(-2.6), 0.0);
        assert_eq!(PlyScalar::Int.coerce(-2.5), -3.0);
    }
}
