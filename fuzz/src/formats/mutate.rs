//! Byte damage: the mutations applied to a serialised file's bytes.

use super::Files;

// ---------------------------------------------------------------------------------
// Byte damage

/// One change to a file's bytes; positions are taken modulo the length.
#[derive(Debug, Clone, PartialEq)]
pub enum Mutation {
    Flip { at: usize, bit: u8 },
    Truncate { at: usize },
    Insert { at: usize, bytes: Vec<u8> },
    Overwrite { at: usize, bytes: Vec<u8> },
    Repeat { from: usize, len: usize, to: usize },
}

/// Byte strings worth inserting: numbers at the edges, JSON and PLY punctuation.
pub const TOKENS: &[&[u8]] = &[
    b"9999999999",
    b"-1",
    b"1e309",
    b"-0",
    b"NaN",
    b"0",
    b"[",
    b"]",
    b"{",
    b"}",
    b"\"",
    b",",
    b"\n",
    b"end_header\n",
    b"\xff\xff\xff\x7f",
    b"4294967295",
    b"1e-320",
    b"1e300",
    b"null",
    b"\x0b",
    b"\x0c",
    "\u{a0}".as_bytes(),
];

/// Applies `ms` in turn (a file never grows past 1 MiB by them).
pub fn mutate(bytes: &mut Vec<u8>, ms: &[Mutation]) {
    for m in ms {
        let n = bytes.len();
        match m {
            Mutation::Flip { at, bit } => {
                if n > 0 {
                    bytes[at % n] ^= 1 << (bit % 8);
                }
            }
            Mutation::Truncate { at } => bytes.truncate(at % (n + 1)),
            Mutation::Insert { at, bytes: b } => {
                if n + b.len() <= 1 << 20 {
                    let i = at % (n + 1);
                    bytes.splice(i..i, b.iter().copied());
                }
            }
            Mutation::Overwrite { at, bytes: b } => {
                if n > 0 {
                    let i = at % n;
                    for (k, &v) in b.iter().enumerate().take(n - i) {
                        bytes[i + k] = v;
                    }
                }
            }
            Mutation::Repeat { from, len, to } => {
                if n > 0 && n <= 1 << 19 {
                    let f = from % n;
                    let l = (len % 256).min(n - f);
                    let piece = bytes[f..f + l].to_vec();
                    let t = to % (n + 1);
                    bytes.splice(t..t, piece);
                }
            }
        }
    }
}

/// Mutates the `target`-th file of `files` (modulo their number).
pub fn mutate_files(files: &mut Files, target: usize, ms: &[Mutation]) {
    if ms.is_empty() || files.is_empty() {
        return;
    }
    let key = files.keys().nth(target % files.len()).cloned().expect("in range");
    mutate(files.get_mut(&key).expect("present"), ms);
}

/// Text from damaged bytes (invalid UTF-8 replaced).
pub fn text_of(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}
