//! PNG by hand (chunks, stored deflate blocks), the mask and image specs written
//! as PNG files, and the PNG readers' driver.

use super::dump;
use localisebot::io;

// ---------------------------------------------------------------------------------
// PNG by hand

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
        }
    }
    !c
}

fn adler32(bytes: &[u8]) -> u32 {
    let (mut a, mut b) = (1u32, 0u32);
    for &x in bytes {
        a = (a + x as u32) % 65521;
        b = (b + a) % 65521;
    }
    (b << 16) | a
}

/// zlib data of `raw` in stored (uncompressed) deflate blocks.
pub fn zlib_stored(raw: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = if raw.is_empty() {
        vec![&[][..]]
    } else {
        raw.chunks(65535).collect()
    };
    for (i, b) in blocks.iter().enumerate() {
        out.push((i + 1 == blocks.len()) as u8);
        let len = b.len() as u16;
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(b);
    }
    out.extend_from_slice(&adler32(raw).to_be_bytes());
    out
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let start = out.len();
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let crc = crc32(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// A PNG file: IHDR of `width`×`height` (`color` type, bit `depth`), optional PLTE and
/// tRNS, one IDAT holding `raw` (filtered scanlines) in stored blocks, IEND.
pub fn png_file(
    width: u32,
    height: u32,
    color: u8,
    depth: u8,
    plte: Option<&[u8]>,
    trns: Option<&[u8]>,
    raw: &[u8],
) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&width.to_be_bytes());
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[depth, color, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    if let Some(p) = plte {
        chunk(&mut out, b"PLTE", p);
    }
    if let Some(t) = trns {
        chunk(&mut out, b"tRNS", t);
    }
    chunk(&mut out, b"IDAT", &zlib_stored(raw));
    chunk(&mut out, b"IEND", &[]);
    out
}

/// The PNG pixel formats a mask may come in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PngKind {
    Gray1,
    Gray8,
    Gray16,
    GrayAlpha8,
    Rgb8,
    Rgba8,
    Rgba16,
    Palette1,
    Palette8,
}

pub const PNG_KINDS: [PngKind; 9] = [
    PngKind::Gray1,
    PngKind::Gray8,
    PngKind::Gray16,
    PngKind::GrayAlpha8,
    PngKind::Rgb8,
    PngKind::Rgba8,
    PngKind::Rgba16,
    PngKind::Palette1,
    PngKind::Palette8,
];

impl PngKind {
    /// (colour type, bit depth).
    pub fn header(self) -> (u8, u8) {
        match self {
            PngKind::Gray1 => (0, 1),
            PngKind::Gray8 => (0, 8),
            PngKind::Gray16 => (0, 16),
            PngKind::GrayAlpha8 => (4, 8),
            PngKind::Rgb8 => (2, 8),
            PngKind::Rgba8 => (6, 8),
            PngKind::Rgba16 => (6, 16),
            PngKind::Palette1 => (3, 1),
            PngKind::Palette8 => (3, 8),
        }
    }
}

/// A mask: a PNG of `kind`, `width`×`height`, whose reading by the SPEC rule is `bits`
/// (row-major, non-zero = object; repeated cyclically when short, all background
/// when empty).
#[derive(Debug, Clone, PartialEq)]
pub struct MaskSpec {
    pub kind: PngKind,
    pub width: u32,
    pub height: u32,
    pub bits: Vec<u8>,
}

impl MaskSpec {
    /// The 0/1 pixels the mask should read as.
    pub fn pixels(&self) -> Vec<u8> {
        let n = self.width as usize * self.height as usize;
        (0..n)
            .map(|i| {
                if self.bits.is_empty() {
                    0
                } else {
                    (self.bits[i % self.bits.len()] != 0) as u8
                }
            })
            .collect()
    }

    pub fn png(&self) -> Vec<u8> {
        let (w, h) = (self.width, self.height);
        let px = self.pixels();
        let (color, depth) = self.kind.header();
        let mut raw = Vec::new();
        for y in 0..h as usize {
            raw.push(0);
            let row = &px[y * w as usize..(y + 1) * w as usize];
            match self.kind {
                PngKind::Gray1 | PngKind::Palette1 => {
                    for byte in row.chunks(8) {
                        let mut b = 0u8;
                        for (k, &v) in byte.iter().enumerate() {
                            b |= v << (7 - k);
                        }
                        raw.push(b);
                    }
                }
                PngKind::Palette8 => raw.extend_from_slice(row),
                PngKind::Gray8 => raw.extend(row.iter().map(|&v| v * 255)),
                PngKind::Gray16 => raw.extend(row.iter().flat_map(|&v| [v * 255; 2])),
                PngKind::GrayAlpha8 => raw.extend(row.iter().flat_map(|&v| [v * 255; 2])),
                PngKind::Rgb8 => raw.extend(row.iter().flat_map(|&v| [v * 255; 3])),
                PngKind::Rgba8 => raw.extend(row.iter().flat_map(|&v| [v * 255; 4])),
                PngKind::Rgba16 => raw.extend(row.iter().flat_map(|&v| [v * 255; 8])),
            }
        }
        let plte =
            matches!(self.kind, PngKind::Palette1 | PngKind::Palette8).then_some(&[0u8, 0, 0, 255, 255, 255][..]);
        png_file(w, h, color, depth, plte, None, &raw)
    }
}

/// A photograph: `rgb` repeated cyclically over the pixels (grey 128 when empty);
/// RGBA8 with alpha from `alpha` (0/1 bits, as [`MaskSpec::bits`]) when given, else
/// RGB8.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageSpec {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
    pub alpha: Option<Vec<u8>>,
}

impl ImageSpec {
    pub fn png(&self) -> Vec<u8> {
        let (w, h) = (self.width as usize, self.height as usize);
        let c = |i: usize| {
            if self.rgb.is_empty() {
                128
            } else {
                self.rgb[i % self.rgb.len()]
            }
        };
        let a = |i: usize| match &self.alpha {
            Some(b) if !b.is_empty() => (b[i % b.len()] != 0) as u8 * 255,
            _ => 0,
        };
        let mut raw = Vec::new();
        for y in 0..h {
            raw.push(0);
            for x in 0..w {
                let i = y * w + x;
                raw.extend_from_slice(&[c(3 * i), c(3 * i + 1), c(3 * i + 2)]);
                if self.alpha.is_some() {
                    raw.push(a(i));
                }
            }
        }
        let color = if self.alpha.is_some() { 6 } else { 2 };
        png_file(self.width, self.height, color, 8, None, None, &raw)
    }
}

// ---------------------------------------------------------------------------------
// PNG readers

/// Decodes `bytes` as a mask and as an image (unsized and sized to `expect`), as
/// the scene loader and the importers do; checks what they give.
pub fn drive_png(
    bytes: &[u8],
    expect: (u32, u32),
) -> (
    localisebot::Result<localisebot::Mask>,
    localisebot::Result<localisebot::Rgba>,
) {
    dump("m.png", bytes);
    let m = io::mask::decode_mask(bytes, "v", "m.png");
    if let Ok(m) = &m {
        assert_eq!(m.data.len(), m.width as usize * m.height as usize);
        assert!(m.data.iter().all(|&v| v <= 1));
    }
    let i = io::mask::decode_image(bytes, "v", "i.png");
    if let Ok(i) = &i {
        assert_eq!(i.data.len(), 4 * i.width as usize * i.height as usize);
    }
    if let Ok(s) = io::mask::decode_mask_sized(bytes, "v", "m.png", expect.0, expect.1) {
        assert_eq!((s.width, s.height), expect);
    }
    if let Ok(s) = io::mask::decode_image_sized(bytes, "v", "i.png", expect.0, expect.1) {
        assert_eq!((s.width, s.height), expect);
    }
    let _ = io::mask::dimensions(bytes);
    (m, i)
}
