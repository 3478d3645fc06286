//! A big-endian bit reader over an RTCM 3 payload (RTCM 10403.3 §3.3:
//! every data field is sent most significant bit first, fields packed
//! without padding). Reads never panic: a field that runs past the end of
//! the payload is the typed [`BitsError::PastEnd`].

/// Why a field could not be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BitsError {
    /// The field ends past the payload.
    PastEnd {
        /// Bit offset of the field.
        offset_bits: usize,
        /// Width of the field.
        width_bits: u32,
        /// Bits in the payload.
        len_bits: usize,
    },
    /// A width outside 1..=64 was asked for.
    Width { width_bits: u32 },
}

impl core::fmt::Display for BitsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            BitsError::PastEnd {
                offset_bits,
                width_bits,
                len_bits,
            } => write!(
                f,
                "a {width_bits}-bit field at bit {offset_bits} runs past the {len_bits}-bit payload"
            ),
            BitsError::Width { width_bits } => {
                write!(f, "field width {width_bits} bits outside 1..=64")
            }
        }
    }
}

/// A cursor over a payload's bits, most significant bit of byte 0 first.
#[derive(Debug, Clone, Copy)]
pub struct BitReader<'a> {
    data: &'a [u8],
    pos_bits: usize,
}

impl<'a> BitReader<'a> {
    /// A reader at bit 0 of `data`.
    pub const fn new(data: &'a [u8]) -> Self {
        BitReader { data, pos_bits: 0 }
    }

    /// A reader at bit `pos_bits` of `data` (a position past the end makes
    /// every read an error).
    pub const fn at(data: &'a [u8], pos_bits: usize) -> Self {
        BitReader { data, pos_bits }
    }

    /// The bit position of the next read.
    pub const fn position_bits(&self) -> usize {
        self.pos_bits
    }

    /// Bits in the payload.
    pub const fn len_bits(&self) -> usize {
        self.data.len() * 8
    }

    /// Whether `width_bits` more bits are in the payload.
    pub fn has(&self, width_bits: usize) -> bool {
        self.pos_bits
            .checked_add(width_bits)
            .is_some_and(|end| end <= self.len_bits())
    }

    /// Skip `width_bits` bits (checked: past the end is an error).
    pub fn skip(&mut self, width_bits: u32) -> Result<(), BitsError> {
        self.check(width_bits)?;
        self.pos_bits += width_bits as usize;
        Ok(())
    }

    fn check(&self, width_bits: u32) -> Result<(), BitsError> {
        if self.has(width_bits as usize) {
            Ok(())
        } else {
            Err(BitsError::PastEnd {
                offset_bits: self.pos_bits,
                width_bits,
                len_bits: self.len_bits(),
            })
        }
    }

    /// An unsigned field of `width_bits` (1..=64) bits.
    pub fn u(&mut self, width_bits: u32) -> Result<u64, BitsError> {
        if !(1..=64).contains(&width_bits) {
            return Err(BitsError::Width { width_bits });
        }
        self.check(width_bits)?;
        let mut v: u64 = 0;
        let mut left = width_bits;
        while left > 0 {
            let byte = self.data.get(self.pos_bits / 8).copied().unwrap_or(0);
            let used = (self.pos_bits % 8) as u32;
            let avail = 8 - used;
            let take = avail.min(left);
            // The `take` bits after the first `used` of this byte.
            let bits = (u32::from(byte) >> (avail - take)) & ((1u32 << take) - 1);
            v = (v << take) | u64::from(bits);
            left -= take;
            self.pos_bits += take as usize;
        }
        Ok(v)
    }

    /// A two's complement signed field of `width_bits` (1..=64) bits.
    pub fn i(&mut self, width_bits: u32) -> Result<i64, BitsError> {
        let v = self.u(width_bits)?;
        let shift = 64 - width_bits;
        // Sign extension: the field's top bit to bit 63, then back.
        Ok(((v << shift) as i64) >> shift)
    }

    /// A sign-magnitude field of `width_bits` (2..=64) bits (RTCM's
    /// GLONASS fields, e.g. DF111-DF124): the top bit is the sign, the rest
    /// the magnitude; a negative zero reads as 0.
    pub fn sm(&mut self, width_bits: u32) -> Result<i64, BitsError> {
        if !(2..=64).contains(&width_bits) {
            return Err(BitsError::Width { width_bits });
        }
        let v = self.u(width_bits)?;
        let magnitude = (v & (u64::MAX >> (65 - width_bits))) as i64;
        if v >> (width_bits - 1) == 1 {
            Ok(-magnitude)
        } else {
            Ok(magnitude)
        }
    }

    /// An unsigned field of at most 32 bits.
    pub fn u32(&mut self, width_bits: u32) -> Result<u32, BitsError> {
        if width_bits > 32 {
            return Err(BitsError::Width { width_bits });
        }
        self.u(width_bits).map(|v| v as u32)
    }

    /// An unsigned field of at most 8 bits.
    pub fn u8(&mut self, width_bits: u32) -> Result<u8, BitsError> {
        if width_bits > 8 {
            return Err(BitsError::Width { width_bits });
        }
        self.u(width_bits).map(|v| v as u8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DATA: [u8; 8] = [
        0b1100_0011,
        0b1001_1010,
        0b1110_0011,
        0b1010_1010,
        0b1111_0000,
        0b1100_1100,
        0b1111_1110,
        0b1100_0011,
    ];

    #[test]
    fn unsigned_fields_across_bytes() {
        assert_eq!(BitReader::at(&DATA, 15).u(10), Ok(0b01_1100_0111));
        assert_eq!(BitReader::at(&DATA, 13).u(2), Ok(0b01));
        assert_eq!(BitReader::new(&DATA).u(12), Ok(0b1100_0011_1001));
        assert_eq!(BitReader::at(&DATA, 42).u(6), Ok(0b00_1100));
        assert_eq!(
            BitReader::new(&DATA).u(48),
            Ok(0b1100_0011_1001_1010_1110_0011_1010_1010_1111_0000_1100_1100)
        );
        assert_eq!(
            BitReader::at(&DATA, 4).u(32),
            Ok(0b0011_1001_1010_1110_0011_1010_1010_1111)
        );
        assert_eq!(BitReader::new(&DATA).u(64), Ok(u64::from_be_bytes(DATA)));
    }

    #[test]
    fn signed_and_sign_magnitude() {
        // Bits 18..23 are 1_0001: -15 in two's complement, -1 in
        // sign-magnitude.
        assert_eq!(BitReader::at(&DATA, 18).i(5), Ok(-15));
        assert_eq!(BitReader::at(&DATA, 18).sm(5), Ok(-1));
        // 0_1100 (bits 42..47 minus the last): positive either way.
        assert_eq!(BitReader::at(&DATA, 42).i(5), Ok(0b0_0110));
        assert_eq!(BitReader::at(&DATA, 42).sm(5), Ok(0b0_0110));
        // Negative zero in sign-magnitude reads as 0.
        assert_eq!(BitReader::new(&[0x80]).sm(8), Ok(0));
        assert_eq!(BitReader::new(&[0xff]).i(8), Ok(-1));
        assert_eq!(BitReader::new(&[0xff]).sm(8), Ok(-127));
        assert_eq!(
            BitReader::new(&[0x80; 8]).i(64),
            Ok(i64::from_be_bytes([0x80; 8]))
        );
    }

    #[test]
    fn past_the_end_is_a_typed_error_and_does_not_move() {
        let mut r = BitReader::at(&DATA, 60);
        assert_eq!(
            r.u(5),
            Err(BitsError::PastEnd {
                offset_bits: 60,
                width_bits: 5,
                len_bits: 64
            })
        );
        assert_eq!(r.position_bits(), 60);
        assert_eq!(r.u(4), Ok(0b0011));
        assert!(r.u(1).is_err());
        assert!(r.skip(1).is_err());
        assert!(BitReader::at(&DATA, usize::MAX).u(1).is_err());
        assert_eq!(
            BitReader::new(&DATA).u(0),
            Err(BitsError::Width { width_bits: 0 })
        );
        assert_eq!(
            BitReader::new(&DATA).u(65),
            Err(BitsError::Width { width_bits: 65 })
        );
        assert!(BitReader::new(&[]).u(1).is_err());
    }
}
