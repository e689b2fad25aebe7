//! Labels on the command line's side-by-side pictures (`terrain synth --preview`): upper
//! case words in a 5×7 bitmap font, drawn dark on a light 8-bit gray image.

/// The 5×7 glyphs of the letters the labels use, one row per byte (bit 4 the leftmost
/// column); a letter without a glyph is drawn as a blank.
const GLYPHS: &[(char, [u8; 7])] = &[
    ('A', [0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11]),
    ('B', [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E]),
    ('E', [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F]),
    ('L', [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F]),
    ('M', [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11]),
    ('P', [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10]),
    ('R', [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11]),
    ('S', [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E]),
    ('T', [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04]),
    ('U', [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E]),
    ('X', [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11]),
];

/// Height in pixels of a label drawn at `scale` (7 rows of `scale` pixels).
pub fn height(scale: usize) -> usize {
    7 * scale
}

/// Draw `text` (upper case) into the `w`-wide image `img` with its top left corner at
/// (`x0`, `y0`), each font pixel a `scale`×`scale` block of black; letters 6 font pixels
/// apart. Whatever falls outside the image is not drawn.
pub fn draw(img: &mut [u8], w: usize, x0: usize, y0: usize, text: &str, scale: usize) {
    let h = img.len() / w.max(1);
    for (i, c) in text.chars().enumerate() {
        let Some((_, rows)) = GLYPHS.iter().find(|(g, _)| *g == c.to_ascii_uppercase()) else {
            continue;
        };
        let cx = x0 + i * 6 * scale;
        for (ry, bits) in rows.iter().enumerate() {
            for rx in 0..5 {
                if bits & (0x10 >> rx) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let (x, y) = (cx + rx * scale + dx, y0 + ry * scale + dy);
                        if x < w && y < h {
                            img[y * w + x] = 0;
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_label_is_drawn_where_asked_and_clipped() {
        let (w, h) = (40, 10);
        let mut img = vec![255u8; w * h];
        draw(&mut img, w, 1, 1, "TE", 1);
        // T's top bar: columns 1..6 of row 1; E's top bar from column 7
        assert!(img[w + 1..w + 6].iter().all(|&v| v == 0));
        assert!(img[w + 7..w + 12].iter().all(|&v| v == 0));
        assert_eq!(img[w + 6], 255);
        // nothing outside the glyphs' rows
        assert!(img[..w].iter().all(|&v| v == 255));
        // clipped at the right edge, no panic
        draw(&mut img, w, 36, 5, "EXAMPLE", 2);
    }
}
