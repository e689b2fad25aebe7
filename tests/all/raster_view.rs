//! Borrowed rasters ([`RasterView`]): coding and comparing samples where they are gives
//! exactly what the owned raster gives, on every sample type, with voids, tiled or not.

use mra::codec::{self, EncodeOptions, Rate};
use mra::io::{DataKind, Metadata, Raster, RasterView, SampleType, Samples, SamplesRef};
use mra::metrics;

const TYPES: [SampleType; 9] = SampleType::ALL;

/// A smooth field with texture in `ty` (values within every type's range).
fn field(dims: &[usize], channels: usize, ty: SampleType, seed: u64) -> Raster {
    let n: usize = dims.iter().product::<usize>() * channels;
    let v: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 + seed as f64 * 7.3;
            60.0 + 40.0 * (t * 0.013).sin() + 10.0 * (t * 0.37).cos()
        })
        .collect();
    let kind = if dims.len() == 3 {
        DataKind::Volume
    } else {
        DataKind::Image
    };
    Raster::new(dims.to_vec(), channels, Samples::from_f64(&v, ty), kind).unwrap()
}

fn rates() -> Vec<Rate> {
    vec![
        Rate::Lossless,
        Rate::Quality(60.0),
        Rate::MaxError(2.0),
        Rate::Bpp(1.0),
        Rate::Psnr(40.0),
    ]
}

#[test]
fn a_view_encodes_to_the_bytes_of_the_owned_raster() {
    for ty in TYPES {
        for (dims, c) in [(vec![37, 29], 3), (vec![9, 13, 11], 1), (vec![50], 1)] {
            let r = field(&dims, c, ty, 1);
            for rate in rates() {
                let opts = EncodeOptions {
                    rate,
                    ..Default::default()
                };
                let owned = codec::encode(&r, &opts).unwrap();
                let view = codec::encode_view(&r.view(), &opts).unwrap();
                assert_eq!(owned, view, "{ty:?} {dims:?}×{c} {rate:?}");
            }
        }
    }
}

#[test]
fn a_view_of_memory_the_caller_owns_encodes_like_a_raster() {
    // samples in a plain slice (as a NumPy array's), never moved into a Raster
    let dims = [24usize, 40];
    let v: Vec<u16> = (0..24 * 40).map(|i| ((i * 37) % 4000) as u16).collect();
    let meta = Metadata::default();
    let view = RasterView::new(&dims, 1, SamplesRef::U16(&v), DataKind::Image, &meta).unwrap();
    let owned = Raster::new(dims.to_vec(), 1, Samples::U16(v.clone()), DataKind::Image).unwrap();
    for rate in rates() {
        let opts = EncodeOptions {
            rate,
            ..Default::default()
        };
        assert_eq!(
            codec::encode_view(&view, &opts).unwrap(),
            codec::encode(&owned, &opts).unwrap(),
            "{rate:?}"
        );
    }
    // the tiled path reads the view a slab at a time
    let opts = EncodeOptions::default();
    assert_eq!(
        codec::encode_tiled_view(&view, &opts, &[10, 16]).unwrap(),
        codec::encode_tiled(&owned, &opts, &[10, 16]).unwrap()
    );
}

#[test]
fn a_view_with_voids_encodes_like_the_owned_raster() {
    let mut r = field(&[31, 33], 1, SampleType::I16, 2);
    if let Samples::I16(v) = &mut r.samples {
        for i in (0..v.len()).step_by(17) {
            v[i] = -32768;
        }
    }
    r.meta.nodata = Some(-32768.0);
    for rate in [Rate::Lossless, Rate::MaxError(1.0), Rate::Quality(70.0)] {
        let opts = EncodeOptions {
            rate,
            ..Default::default()
        };
        assert_eq!(
            codec::encode(&r, &opts).unwrap(),
            codec::encode_view(&r.view(), &opts).unwrap(),
            "{rate:?}"
        );
    }
}

#[test]
fn a_view_checks_its_sample_count() {
    let v = [1u8, 2, 3];
    let meta = Metadata::default();
    let e = RasterView::new(&[2, 2], 1, SamplesRef::U8(&v), DataKind::Image, &meta);
    assert!(e.is_err());
    let e = RasterView::new(&[0, 3], 1, SamplesRef::U8(&v), DataKind::Image, &meta);
    assert!(e.is_err());
}

#[test]
fn views_compare_as_the_owned_rasters() {
    for ty in TYPES {
        let a = field(&[20, 21], 3, ty, 3);
        let b = field(&[20, 21], 3, ty, 4);
        let owned = metrics::compare(&a, &b, &Default::default()).unwrap();
        let view = metrics::compare_view(&a.view(), &b.view(), &Default::default()).unwrap();
        assert_eq!(owned, view, "{ty:?}");
        assert!(owned.psnr.unwrap().is_finite());
    }
}

#[test]
fn a_view_round_trips_to_an_owned_raster() {
    let mut r = field(&[5, 6, 7], 2, SampleType::F32, 5);
    r.meta.spacing = Some(vec![2.0, 0.5, 0.5]);
    r.meta.origin = Some(vec![1.0, 2.0, 3.0]);
    assert_eq!(r.view().to_owned(), r);
    assert_eq!(r.view().positions(), 5 * 6 * 7);
    assert_eq!(r.samples.view().min_max(), r.samples.min_max());
}

#[test]
fn views_resample_as_the_owned_rasters() {
    use mra::progress::Progress;
    use mra::scheme::{Boundary, Scheme};
    use mra::upscale::{self, Method};
    for ty in [
        SampleType::U8,
        SampleType::U16,
        SampleType::F32,
        SampleType::F64,
    ] {
        let mut r = field(&[23, 18], 2, ty, 6);
        r.meta.spacing = Some(vec![0.5, 0.25]);
        let plans = upscale::plan_raster(&r.dims, &[0, 1], Some(2), None, false).unwrap();
        let m = Method::default();
        let up_view = upscale::upscale_view(&r.view(), &m, &plans, &Progress::hidden()).unwrap();
        let up_owned = upscale::upscale_raster(r.clone(), &m, &plans, &Progress::hidden()).unwrap();
        assert_eq!(up_view, up_owned, "{ty:?}");
        let down_view =
            upscale::downscale_view(&r.view(), Scheme::Cubic, Boundary::Symmetric, 1, &[0, 1])
                .unwrap();
        let down_owned =
            upscale::downscale_raster(r.clone(), Scheme::Cubic, Boundary::Symmetric, 1, &[0, 1])
                .unwrap();
        assert_eq!(down_view, down_owned, "{ty:?}");
        assert_eq!(down_view.dims, vec![12, 9]);
    }
}
