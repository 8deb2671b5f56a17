//! Mutations of an input: the byte-level ones of AFL/libFuzzer (bit flips, interesting
//! integers, block deletion, duplication and splicing) and text-level ones for the formats
//! that are text (a number replaced by a hostile one, a token of the format inserted).

use rand::{Rng, RngExt};

/// Integers that find off-by-ones and overflows, as 1, 2, 4 and 8 byte fields.
const INTERESTING: [i64; 14] = [
    0,
    1,
    -1,
    2,
    127,
    128,
    255,
    256,
    65_535,
    65_536,
    100_000,
    i32::MAX as i64,
    i32::MIN as i64,
    i64::MAX,
];

/// Numbers, as text, that a reader of numbers must survive.
const HOSTILE_NUMBERS: [&str; 20] = [
    "0",
    "-0",
    "1",
    "-1",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e30",
    "-1e30",
    "1e-40",
    "1e308",
    "1e400",
    "100000",
    "4294967296",
    "18446744073709551616",
    "99999999999999999999999",
    "0.5",
    "-2147483648",
    "",
];

/// Mutates `input` in place with 1 to 4 stacked mutations; `others` (the corpus) for
/// splicing, `dictionary` for the format's tokens; the result is at most `max_len` bytes.
pub fn mutate(
    input: &mut Vec<u8>,
    others: &[Vec<u8>],
    dictionary: &[&[u8]],
    max_len: usize,
    rng: &mut impl Rng,
) {
    let rounds = 1 + rng.random_range(0..4);
    for _ in 0..rounds {
        mutate_once(input, others, dictionary, rng);
    }
    input.truncate(max_len);
    // A PNG with a wrong chunk CRC stops at the first check; most of the time the mutant gets
    // its CRCs back, so that a changed header (a 2^31-pixel width) reaches the decoder.
    if input.starts_with(PNG_SIGNATURE) && rng.random_bool(0.9) {
        fix_png_crcs(input);
    }
}

const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// Rewrites the CRC of every whole chunk of a PNG (length, type, data, CRC after the
/// signature); a chunk cut short by the end of the input is left as it is.
pub fn fix_png_crcs(png: &mut [u8]) {
    let mut at = PNG_SIGNATURE.len();
    while at + 8 <= png.len() {
        let length = u32::from_be_bytes([png[at], png[at + 1], png[at + 2], png[at + 3]]);
        let Some(end) = usize::try_from(length)
            .ok()
            .and_then(|l| (at + 8).checked_add(l))
        else {
            return;
        };
        if end + 4 > png.len() {
            return;
        }
        let crc = crc32fast::hash(&png[at + 4..end]);
        png[end..end + 4].copy_from_slice(&crc.to_be_bytes());
        at = end + 4;
    }
}

fn mutate_once(input: &mut Vec<u8>, others: &[Vec<u8>], dictionary: &[&[u8]], rng: &mut impl Rng) {
    if input.is_empty() {
        input.push(rng.random());
        return;
    }
    let len = input.len();
    let at = rng.random_range(0..len);
    match rng.random_range(0..12) {
        0 => input[at] ^= 1 << rng.random_range(0..8),
        1 => input[at] = rng.random(),
        2 => {
            let value = INTERESTING[rng.random_range(0..INTERESTING.len())];
            let width = [1, 2, 4, 8][rng.random_range(0..4)];
            let bytes = if rng.random_bool(0.5) {
                value.to_le_bytes()
            } else {
                (value << (64 - 8 * width)).to_be_bytes()
            };
            let end = (at + width).min(len);
            input[at..end].copy_from_slice(&bytes[..end - at]);
        }
        3 => {
            // Delete a block.
            let end = (at + 1 + rng.random_range(0..(len - at).min(64))).min(len);
            input.drain(at..end);
        }
        4 => {
            // Duplicate a block.
            let end = (at + 1 + rng.random_range(0..(len - at).min(64))).min(len);
            let block = input[at..end].to_vec();
            let to = rng.random_range(0..=input.len());
            input.splice(to..to, block);
        }
        5 => input.truncate(at),
        6 => {
            // Splice with another input of the corpus.
            if let Some(other) = others.get(rng.random_range(0..others.len().max(1)))
                && !other.is_empty()
            {
                let from = rng.random_range(0..other.len());
                input.truncate(at);
                input.extend_from_slice(&other[from..]);
            }
        }
        7 | 8 => replace_number(input, at, rng),
        9 | 10 => {
            if !dictionary.is_empty() {
                let token = dictionary[rng.random_range(0..dictionary.len())];
                if rng.random_bool(0.5) {
                    input.splice(at..at, token.iter().copied());
                } else {
                    let end = (at + token.len()).min(len);
                    input.splice(at..end, token.iter().copied());
                }
            }
        }
        _ => {
            // Insert random bytes.
            let count = 1 + rng.random_range(0..8);
            let bytes: Vec<u8> = (0..count).map(|_| rng.random()).collect();
            input.splice(at..at, bytes);
        }
    }
}

/// Replaces the decimal number at or after `from` (digits, sign, point, exponent) by a
/// hostile one; inserts one at `from` when there is none.
fn replace_number(input: &mut Vec<u8>, from: usize, rng: &mut impl Rng) {
    let hostile = HOSTILE_NUMBERS[rng.random_range(0..HOSTILE_NUMBERS.len())].as_bytes();
    let is_digit = |b: u8| b.is_ascii_digit();
    let Some(start) = input[from..]
        .iter()
        .position(|&b| is_digit(b))
        .map(|i| i + from)
    else {
        input.splice(from..from, hostile.iter().copied());
        return;
    };
    let start = if start > 0 && input[start - 1] == b'-' {
        start - 1
    } else {
        start
    };
    let part_of_number = |b: u8| is_digit(b) || matches!(b, b'.' | b'e' | b'E' | b'+' | b'-');
    let end = input[start + 1..]
        .iter()
        .position(|&b| !part_of_number(b))
        .map_or(input.len(), |i| i + start + 1);
    input.splice(start..end, hostile.iter().copied());
}

#[cfg(test)]
mod tests {
    #[test]
    fn png_crcs_are_rewritten_over_whole_chunks() {
        // IEND's CRC is that of its type alone: AE 42 60 82.
        let mut png = super::PNG_SIGNATURE.to_vec();
        png.extend_from_slice(&[0, 0, 0, 0, b'I', b'E', b'N', b'D', 0, 0, 0, 0]);
        png.extend_from_slice(&[0, 0, 0, 9, b'I']); // a chunk cut short: left alone
        super::fix_png_crcs(&mut png);
        assert_eq!(png[16..20], [0xAE, 0x42, 0x60, 0x82]);
        assert_eq!(png[20..], [0, 0, 0, 9, b'I']);
    }

    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn mutations_stay_within_the_length_and_change_inputs() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let seed = b"{\"fx\": 525.0, \"width\": 640}".to_vec();
        let mut changed = 0;
        for _ in 0..2000 {
            let mut input = seed.clone();
            mutate(
                &mut input,
                std::slice::from_ref(&seed),
                &[b"\"fy\""],
                40,
                &mut rng,
            );
            assert!(input.len() <= 40);
            changed += usize::from(input != seed);
        }
        assert!(
            changed > 1900,
            "only {changed} of 2000 mutations changed the input"
        );
    }

    #[test]
    fn a_number_is_replaced_whole() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut input = b"fx -525.25e3 end".to_vec();
        replace_number(&mut input, 0, &mut rng);
        let text = String::from_utf8_lossy(&input);
        assert!(text.starts_with("fx ") && text.ends_with(" end"), "{text}");
        assert!(!text.contains("525"), "{text}");
    }
}
