//! Rules the library owns, so that the command line, Python and the server only translate:
//! a decode level the file does not hold is the library's typed error (never a clamp),
//! and an upscale over the memory budget is refused by the library before it allocates.

use mra::codec::{self, DecodeOptions, EncodeOptions, Rate};
use mra::io::{DataKind, Raster, Samples};
use mra::upscale::{self, Method};
use mra::{Error, ErrorKind};

fn image(h: usize, w: usize) -> Raster {
    let px = (0..h * w).map(|i| ((i * 37) % 251) as u8).collect();
    Raster::new(vec![h, w], 1, Samples::U8(px), DataKind::Image).unwrap()
}

fn level(k: usize) -> DecodeOptions {
    DecodeOptions {
        level: k,
        ..Default::default()
    }
}

/// Levels 0 ..= depth decode; depth + 1 is `Error::Level` naming both numbers, from every
/// entry (bytes, a file, a file in slabs), for a file of one tile and a tiled one.
#[test]
fn a_decode_level_the_file_lacks_is_a_typed_error_not_a_clamp() {
    let r = image(40, 56);
    let o = EncodeOptions {
        levels: 3,
        rate: Rate::Quality(60.0),
        ..Default::default()
    };
    let dir = std::env::temp_dir().join(format!("mra-rules-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in [
        ("one.mra", codec::encode(&r, &o).unwrap()),
        ("tiled.mra", codec::encode_tiled(&r, &o, &[16, 32]).unwrap()),
    ] {
        let depth = codec::depth_of(&codec::header_of(&bytes).unwrap()).unwrap();
        assert!(depth >= 1, "{name}");
        assert!(codec::decode(&bytes, &level(depth)).is_ok(), "{name}");
        let f = dir.join(name);
        std::fs::write(&f, &bytes).unwrap();
        let errors = [
            codec::decode(&bytes, &level(depth + 1)).err(),
            codec::decode_file(&f, &level(depth + 1)).err(),
            codec::SlabDecoder::open(&f, &level(depth + 1)).err(),
        ];
        for e in errors {
            let e = e.unwrap_or_else(|| panic!("{name}: level {} decoded", depth + 1));
            assert_eq!(e.kind(), ErrorKind::Parameter, "{name}: {e}");
            assert!(
                matches!(e, Error::Level { level, levels } if level == depth + 1 && levels == depth),
                "{name}: {e}"
            );
            assert!(
                e.to_string()
                    .contains(&format!("{} of a file with levels 0 to {depth}", depth + 1)),
                "{e}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// ×100 of a 1000 × 1000 image is 10¹⁰ samples, 50 GB in f32 plus u8: over the default
/// budget (8 GiB), refused by the library itself, from a raster and from a view.
#[test]
fn an_upscale_over_the_budget_is_refused_by_the_library_before_allocating() {
    if std::env::var_os(mra::limits::ENV).is_some() {
        eprintln!("skipped: {} is set", mra::limits::ENV);
        return;
    }
    let r = image(1000, 1000);
    let plans = upscale::plan_raster(&r.dims, &[0, 1], Some(100), None, false).unwrap();
    assert_eq!(
        upscale::output_dims(&r.dims, &plans),
        vec![100_000, 100_000]
    );
    let m = Method::default();
    let bar = mra::progress::Progress::hidden();
    let e = upscale::upscale_view(&r.view(), &m, &plans, &bar).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::LimitsExceeded, "{e}");
    assert!(e.to_string().contains("MRA_MAX_BYTES"), "{e}");
    let e = upscale::upscale_raster(r, &m, &plans, &bar).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::LimitsExceeded, "{e}");
}
