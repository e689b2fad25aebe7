//! The code tables of `formats/MRA.md` against the reader and writer: every code the
//! writer writes is in its table with the same name, and every table row is a code the
//! reader decodes to that value (so the spec cannot drift from the code again); and the
//! container's faults come out as typed errors by cause.

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::entropy::codeblocks::Coder;
use mra::format::header::{
    boundary_code, boundary_of, coder_name, kind_code, kind_name, kind_of, mode_code, mode_name,
    mode_of, sample_type_code, sample_type_of, scheme_code, scheme_of, Colour, CODERS, KINDS,
    TYPES,
};
use mra::format::{Mode, Tag, Version};
use mra::scheme::{Boundary, Scheme};
use mra::{ErrorKind, FormatError};
use std::collections::BTreeMap;

fn spec() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("formats/MRA.md");
    std::fs::read_to_string(path).expect("formats/MRA.md")
}

/// The rows (cells trimmed, backticks dropped) of the table after `<!-- table: name -->`.
fn table(text: &str, name: &str) -> Vec<Vec<String>> {
    let marker = format!("<!-- table: {name} -->");
    let at = text
        .find(&marker)
        .unwrap_or_else(|| panic!("formats/MRA.md has no table {name}"));
    let rows: Vec<Vec<String>> = text[at + marker.len()..]
        .lines()
        .skip_while(|l| l.trim().is_empty())
        .take_while(|l| l.trim_start().starts_with('|'))
        .map(|l| {
            l.trim()
                .trim_matches('|')
                .split('|')
                .map(|c| c.trim().replace('`', ""))
                .collect()
        })
        .collect();
    assert!(rows.len() > 2, "table {name} is empty");
    // the header row and the separator
    rows[2..].to_vec()
}

/// `code → name` of a table whose first two columns are those, each code once.
fn codes(text: &str, name: &str) -> BTreeMap<u8, String> {
    let mut m = BTreeMap::new();
    for r in table(text, name) {
        let code: u8 = r[0]
            .parse()
            .unwrap_or_else(|_| panic!("table {name}: code {:?}", r[0]));
        assert!(
            m.insert(code, r[1].clone()).is_none(),
            "table {name}: code {code} twice"
        );
    }
    m
}

/// Both ways: the table is exactly `written` (code → name), and every code the table
/// does not list is refused by `reads`.
fn check(
    name: &str,
    table: &BTreeMap<u8, String>,
    written: &[(u8, &str)],
    reads: impl Fn(u8) -> bool,
) {
    let code: BTreeMap<u8, String> = written.iter().map(|&(c, n)| (c, n.to_string())).collect();
    assert_eq!(
        table, &code,
        "table {name} of formats/MRA.md against the code"
    );
    for c in 0..=255u8 {
        assert_eq!(
            reads(c),
            table.contains_key(&c),
            "{name} code {c}: read iff listed"
        );
    }
}

#[test]
fn spec_tables_match_the_code() {
    let text = spec();

    let kinds: Vec<(u8, &str)> = KINDS
        .iter()
        .map(|&k| (kind_code(k), kind_name(k)))
        .collect();
    check("kinds", &codes(&text, "kinds"), &kinds, |c| {
        kind_of(c).is_some()
    });
    for (c, _) in &kinds {
        assert_eq!(kind_code(kind_of(*c).unwrap()), *c);
    }

    let types: Vec<(u8, &str)> = TYPES
        .iter()
        .map(|&t| (sample_type_code(t), t.name()))
        .collect();
    check("sample-types", &codes(&text, "sample-types"), &types, |c| {
        sample_type_of(c).is_some()
    });
    for (c, n) in &types {
        assert_eq!(sample_type_of(*c).unwrap().name(), *n);
    }

    let colours: Vec<(u8, &str)> = Colour::ALL.iter().map(|c| (c.code(), c.name())).collect();
    check("colour", &codes(&text, "colour"), &colours, |c| {
        Colour::of(c).is_some()
    });

    // the mode byte: every mode, and lossless with its scaled-float code
    let mut modes: Vec<(u8, &str)> = Mode::ALL
        .iter()
        .map(|&m| (mode_code(m, false), mode_name(m, false)))
        .collect();
    modes.push((
        mode_code(Mode::Lossless, true),
        mode_name(Mode::Lossless, true),
    ));
    check("modes", &codes(&text, "modes"), &modes, |c| {
        mode_of(c).is_some()
    });
    for (c, n) in &modes {
        let (m, scaled) = mode_of(*c).unwrap();
        assert_eq!((mode_code(m, scaled), mode_name(m, scaled)), (*c, *n));
    }

    let schemes: Vec<(u8, &str)> = Scheme::ALL
        .iter()
        .map(|&s| (scheme_code(s), s.name()))
        .collect();
    check("schemes", &codes(&text, "schemes"), &schemes, |c| {
        scheme_of(c).is_some()
    });
    for (c, n) in &schemes {
        assert_eq!(scheme_of(*c).unwrap().name(), *n);
    }

    let bounds: Vec<(u8, &str)> = Boundary::ALL
        .iter()
        .map(|&b| (boundary_code(b), b.name()))
        .collect();
    check("boundaries", &codes(&text, "boundaries"), &bounds, |c| {
        boundary_of(c).is_some()
    });

    // the block coders of 3.1: the entropy's enum, the header's names, the spec's table
    let coders: Vec<(u8, &str)> = Coder::ALL.iter().map(|c| (c.id(), c.name())).collect();
    check("coders", &codes(&text, "coders"), &coders, |c| {
        coder_name(c).is_some() && Coder::of(c).is_some()
    });
    for (c, n) in &coders {
        assert_eq!(coder_name(*c), Some(*n));
        assert_eq!(Coder::of(*c).map(Coder::id), Some(*c));
    }
    assert_eq!(CODERS.len(), Coder::ALL.len());

    // chunk types: the same set, the same critical bit
    let rows = table(&text, "chunk-types");
    let listed: BTreeMap<String, bool> =
        rows.iter().map(|r| (r[0].clone(), r[1] == "yes")).collect();
    assert_eq!(listed.len(), rows.len(), "a chunk type twice");
    let known: BTreeMap<String, bool> = Tag::ALL
        .iter()
        .map(|t| (t.name().to_string(), Tag::is_critical(t.bytes())))
        .collect();
    assert_eq!(
        listed, known,
        "chunk types of formats/MRA.md against format::Tag"
    );
    for name in listed.keys() {
        let b: [u8; 4] = name.as_bytes().try_into().expect("four letters");
        assert_eq!(Tag::of(&b).map(Tag::name), Some(name.as_str()));
    }

    // versions: the ones this reader decodes, the latest last
    let versions: Vec<String> = table(&text, "versions")
        .into_iter()
        .map(|r| r[0].clone())
        .collect();
    let code: Vec<String> = Version::ALL.iter().map(|v| v.to_string()).collect();
    assert_eq!(
        versions, code,
        "versions of formats/MRA.md against format::Version::ALL"
    );
    assert_eq!(Version::ALL.last(), Some(&Version::LATEST));
    for v in Version::ALL {
        assert!(v.check().is_ok(), "{v}");
    }
    let after = Version::new(Version::LATEST.major, Version::LATEST.minor + 1);
    assert_eq!(after.check().unwrap_err().kind(), ErrorKind::Unsupported);
}

/// A tap as the spec writes it: a decimal, or `x/y` the f64 quotient of two integers.
fn tap(s: &str) -> f64 {
    match s.split_once('/') {
        Some((x, y)) => x.parse::<f64>().unwrap() / y.parse::<f64>().unwrap(),
        None => s.parse().unwrap_or_else(|_| panic!("tap {s:?}")),
    }
}

#[test]
fn spec_filter_taps_are_the_schemes_bit_for_bit() {
    let text = spec();
    let mut listed = BTreeMap::new();
    for r in table(&text, "scheme-taps") {
        let code: u8 = r[0].parse().unwrap();
        let first: isize = r[2].parse().unwrap();
        let taps: Vec<u64> = r[3].split_whitespace().map(|t| tap(t).to_bits()).collect();
        assert!(
            listed.insert((code, r[1].clone()), (first, taps)).is_none(),
            "scheme {code} filter {} twice",
            r[1]
        );
    }
    let mut code = BTreeMap::new();
    for s in Scheme::ALL {
        let Some(f) = s.regular() else { continue };
        for (name, t) in [("a", f.a), ("b", f.b), ("p", f.p), ("q", f.q)] {
            let bits = t.w.iter().map(|w| w.to_bits()).collect();
            code.insert((scheme_code(s), name.to_string()), (t.first, bits));
        }
    }
    for (k, v) in &code {
        assert_eq!(
            listed.get(k),
            Some(v),
            "scheme {} filter {}: spec against src/scheme",
            k.0,
            k.1
        );
    }
    assert_eq!(
        listed.len(),
        code.len(),
        "the spec lists filters of no scheme"
    );
}

fn small_file() -> Vec<u8> {
    use mra::io::{DataKind, Raster, SampleType, Samples};
    let v: Vec<f64> = (0..120).map(|i| ((i * 37) % 251) as f64).collect();
    let r = Raster::new(
        vec![12, 10],
        1,
        Samples::from_f64(&v, SampleType::U8),
        DataKind::Image,
    )
    .unwrap();
    codec::encode(
        &r,
        &EncodeOptions {
            rate: Rate::Quality(50.0),
            ..Default::default()
        },
    )
    .unwrap()
}

/// The `(start, end)` of each chunk's payload, with its type.
fn chunks(b: &[u8]) -> Vec<([u8; 4], usize, usize)> {
    let mut v = Vec::new();
    let mut at = 8;
    while at + 12 <= b.len() {
        let n = u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
        v.push((b[at + 4..at + 8].try_into().unwrap(), at + 8, at + 8 + n));
        at += n + 12;
    }
    v
}

fn recrc(b: &mut [u8], start: usize, end: usize) {
    let mut c = mra::format::crc::Crc32c::new();
    c.update(&b[start - 4..end]);
    let v = c.finish().to_le_bytes();
    b[end..end + 4].copy_from_slice(&v);
}

fn fault(b: &[u8]) -> String {
    let e = codec::decode(b, &DecodeOptions::default()).unwrap_err();
    let f = e
        .fault()
        .unwrap_or_else(|| panic!("not a container fault: {e}"));
    assert!(!e.to_string().contains('\n'), "one line: {e}");
    format!("{f:?}")
}

#[test]
fn container_faults_are_typed_by_cause() {
    let good = small_file();
    let cause = |b: &[u8]| fault(b).split([' ', '{', '(']).next().unwrap().to_string();

    let mut b = good.clone();
    b[1] = b'X';
    assert_eq!(cause(&b), "Signature");

    let mut b = good.clone();
    let (_, s, _) = chunks(&b)[0];
    // the sample file is format 2: a minor above the latest 2.x
    b[s + 1] = Version::LATEST_2.minor + 1;
    let (_, s, e) = chunks(&b)[0];
    recrc(&mut b, s, e);
    assert_eq!(cause(&b), "Version");

    let mut b = good.clone();
    let (_, s, _) = chunks(&b)[1];
    b[s] ^= 1;
    assert_eq!(cause(&b), "Crc");

    // a LEVL chunk dropped: missing at MEND
    let cs = chunks(&good);
    let (_, s, e) = *cs.iter().find(|c| &c.0 == b"LEVL").unwrap();
    let mut b = good[..s - 8].to_vec();
    b.extend_from_slice(&good[e + 4..]);
    assert!(
        matches!(cause(&b).as_str(), "Missing" | "Order"),
        "{}",
        fault(&b)
    );

    // a second HEAD
    let (_, s, e) = cs[0];
    let mut b = good[..e + 4].to_vec();
    b.extend_from_slice(&good[s - 8..e + 4]);
    b.extend_from_slice(&good[e + 4..]);
    assert_eq!(cause(&b), "Duplicate");

    // the file cut short
    let b = &good[..good.len() - 20];
    assert_eq!(cause(b), "Truncated");

    // an unknown critical chunk
    let mut b = good[..e + 4].to_vec();
    mra::format::put_chunk(&mut b, b"ZZZZ", &[1, 2, 3]);
    b.extend_from_slice(&good[e + 4..]);
    assert_eq!(cause(&b), "UnknownChunk");
    let err = codec::decode(&b, &DecodeOptions::default()).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::Unsupported);
    assert!(err.to_string().contains("ZZZZ"), "{err}");

    // a CRC fault reads as before: the chunk, its offset, the two values
    let mut b = good.clone();
    let (_, s, _) = chunks(&b)[1];
    b[s] ^= 1;
    let e = codec::decode(&b, &DecodeOptions::default()).unwrap_err();
    assert!(matches!(e.fault(), Some(FormatError::Crc { .. })));
    assert!(
        e.to_string().starts_with("CRC-32C mismatch in chunk"),
        "{e}"
    );
}
