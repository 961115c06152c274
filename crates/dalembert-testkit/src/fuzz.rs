//! Structure-aware mutation of text inputs (scene files, result CSVs) for the stable-toolchain fuzz
//! harness (`examples/fuzz.rs`, `tests/fuzz_smoke.rs`): numbers replaced by extreme values, names
//! by other names or junk, lines deleted, duplicated, swapped or spliced from other seeds, array
//! arity changed, bytes inserted or removed, texts truncated.

/// A small deterministic generator (xorshift64*): runs are reproducible from their seed.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator from `seed` (any value; zero is remapped).
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }

    /// One element of `items`.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Values that break naive numeric code, as TOML/CSV would spell them.
const NUMBERS: &[&str] = &[
    "0",
    "-0.0",
    "-1",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "5e-324",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "1e16",
    "3.0e-5",
    "0.5",
    "2",
    "1e200",
    "NaN",
    "1e",
    "+",
    "0x10",
    "1_000",
    "\"1\"",
    "[]",
    "[1, 2]",
    "[[1, 2], [3, 4]]",
    "{ kind = \"constant\" }",
    "true",
];

/// Names and junk for string values.
const STRINGS: &[&str] = &[
    "\"\"",
    "\"ground\"",
    "\"crank\"",
    "\"rod,evil\"",
    "\"a\\\"quote\"",
    "\"line\\nbreak\"",
    "\"ünïcödé\"",
    "\"revolute\"",
    "\"prismatic\"",
    "\"distance\"",
    "\"gear\"",
    "\"rack-pinion\"",
    "\"joint-angle\"",
    "\"body-coordinate\"",
    "\"spring-damper\"",
    "\"torque\"",
    "\"rk4\"",
    "\"dopri5\"",
    "\"generalized-alpha\"",
    "\"embedding\"",
    "\"amalgamated\"",
    "\"projection\"",
    "\"x\"",
    "\"angle\"",
    "\"linear\"",
    "\"harmonic\"",
    "\"smooth-step\"",
    "\"polynomial\"",
    "1",
    "[\"ground\", \"ground\"]",
];

const BYTES: &[char] = &[
    '[', ']', '{', '}', '=', ',', '"', '\n', '#', '.', '-', 'e', '0', '9', ' ', '\'', 'é', '\0',
];

/// Spans of number-like tokens in `line`.
fn number_spans(line: &str) -> Vec<(usize, usize)> {
    let b = line.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(|c| c.is_ascii_digit()));
        let inside_word = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if starts && !inside_word {
            let s = i;
            i += 1;
            while i < b.len() && (b[i].is_ascii_digit() || b"._eE+-".contains(&b[i])) {
                i += 1;
            }
            spans.push((s, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// Spans of `"…"` string literals in `line`.
fn string_spans(line: &str) -> Vec<(usize, usize)> {
    let idx: Vec<usize> = line.match_indices('"').map(|(i, _)| i).collect();
    idx.chunks(2)
        .filter(|c| c.len() == 2)
        .map(|c| (c[0], c[1] + 1))
        .collect()
}

fn replace_span(line: &str, (s, e): (usize, usize), with: &str) -> String {
    format!("{}{}{}", &line[..s], with, &line[e..])
}

/// One to four mutations of `input`; `seeds` supply lines to splice.
pub fn mutate(rng: &mut Rng, seeds: &[String], input: &str) -> String {
    let mut lines: Vec<String> = input.lines().map(String::from).collect();
    for _ in 0..1 + rng.below(4) {
        if lines.is_empty() {
            lines.push(String::new());
        }
        let k = rng.below(lines.len());
        match rng.below(10) {
            0 | 1 => {
                let spans = number_spans(&lines[k]);
                if !spans.is_empty() {
                    let span = *rng.pick(&spans);
                    let with = *rng.pick(NUMBERS);
                    lines[k] = replace_span(&lines[k], span, with);
                }
            }
            2 => {
                let spans = string_spans(&lines[k]);
                if !spans.is_empty() {
                    let span = *rng.pick(&spans);
                    let with = *rng.pick(STRINGS);
                    lines[k] = replace_span(&lines[k], span, with);
                }
            }
            3 => {
                lines.remove(k);
            }
            4 => {
                let l = lines[k].clone();
                lines.insert(k, l);
            }
            5 => {
                let j = rng.below(lines.len());
                lines.swap(k, j);
            }
            6 => {
                let other: Vec<&str> = rng.pick(seeds).lines().collect();
                if !other.is_empty() {
                    lines[k] = rng.pick(&other).to_string();
                }
            }
            7 => {
                // Array arity: drop or add an element.
                let l = &lines[k];
                if let (Some(open), Some(close)) = (l.find('['), l.rfind(']')) {
                    if open < close {
                        let inner = &l[open + 1..close];
                        let new_inner = if rng.below(2) == 0 {
                            inner.rsplit_once(',').map_or(String::new(), |(a, _)| a.to_string())
                        } else {
                            format!("{inner}, {}", *rng.pick(NUMBERS))
                        };
                        lines[k] = format!("{}[{new_inner}]{}", &l[..open], &l[close + 1..]);
                    }
                }
            }
            8 => {
                // A character inserted, removed or replaced.
                let mut chars: Vec<char> = lines[k].chars().collect();
                let at = rng.below(chars.len() + 1);
                match rng.below(3) {
                    0 => chars.insert(at, *rng.pick(BYTES)),
                    1 if at < chars.len() => {
                        chars.remove(at);
                    }
                    _ if at < chars.len() => chars[at] = *rng.pick(BYTES),
                    _ => {}
                }
                lines[k] = chars.into_iter().collect();
            }
            _ => {
                // Truncation.
                lines.truncate(k + 1);
                let cut = rng.below(lines[k].len() + 1);
                let cut = (0..=cut).rev().find(|&c| lines[k].is_char_boundary(c)).unwrap_or(0);
                lines[k].truncate(cut);
            }
        }
    }
    let mut out = lines.join("\n");
    out.push('\n');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutation_is_deterministic_and_changes_the_text() {
        let seed = "[[bodies]]\nname = \"a\"\nmass = 1.0\nposition = [0.5, 0.0]\n".to_string();
        let seeds = vec![seed.clone()];
        let (mut a, mut b) = (Rng::new(7), Rng::new(7));
        let mut changed = 0;
        for _ in 0..200 {
            let (x, y) = (mutate(&mut a, &seeds, &seed), mutate(&mut b, &seeds, &seed));
            assert_eq!(x, y);
            changed += usize::from(x != seed);
        }
        assert!(changed > 150, "{changed} of 200 mutants differ from the seed");
        assert_eq!(number_spans("position = [0.5, -1e3]"), vec![(12, 15), (17, 21)]);
    }
}
