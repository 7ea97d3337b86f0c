//! Sheet stage: cells laid out one band per method, frames across in time order, each band
//! under its label, key cells marked by a bar under them.

use super::font;
use super::raster::{Picture, BACKGROUND};

/// Label glyphs drawn at this many pixels per font pixel; the label row's height in pixels (a
/// glyph with room around it), and the key bar's.
pub const LABEL_SCALE: usize = 2;
pub const LABEL: usize = font::HEIGHT * LABEL_SCALE + 8;
pub const KEY_BAR: usize = 3;
const INK: [u8; 3] = [40, 40, 40];
const KEY: [u8; 3] = [230, 120, 30];
const RULE: [u8; 3] = [200, 200, 196];

/// One band: its label and its cells (pictures of equal size) with whether each is a key.
pub struct Band {
    pub label: String,
    pub cells: Vec<(Picture, bool)>,
}

/// Draw `text` with its top-left corner at (`x`, `y`), `scale` pixels per font pixel.
pub fn text(p: &mut Picture, text: &str, x: usize, y: usize, scale: usize, colour: [u8; 3]) {
    for (i, c) in text.chars().enumerate() {
        for gy in 0..font::HEIGHT * scale {
            for gx in 0..font::WIDTH * scale {
                if font::ink(c, gx / scale, gy / scale) {
                    p.set(x + i * font::ADVANCE * scale + gx, y + gy, colour);
                }
            }
        }
    }
}

/// The sheet of `bands`, cells `cell` = (width, height) pixels, `columns` across.
pub fn compose(bands: &[Band], cell: (usize, usize), columns: usize) -> Picture {
    let band_height = LABEL + cell.1 + KEY_BAR;
    let mut sheet = Picture::new(
        cell.0 * columns.max(1),
        band_height * bands.len(),
        BACKGROUND,
    );
    for (b, band) in bands.iter().enumerate() {
        let top = b * band_height;
        if b > 0 {
            for x in 0..sheet.width {
                sheet.set(x, top, RULE);
            }
        }
        text(
            &mut sheet,
            &band.label,
            6,
            top + (LABEL - font::HEIGHT * LABEL_SCALE) / 2 + 1,
            LABEL_SCALE,
            INK,
        );
        for (i, (picture, key)) in band.cells.iter().enumerate() {
            let x = i * cell.0;
            sheet.paste(picture, x, top + LABEL);
            if *key {
                for dy in 0..KEY_BAR {
                    for dx in 2..cell.0.saturating_sub(2) {
                        sheet.set(x + dx, top + LABEL + cell.1 + dy, KEY);
                    }
                }
            }
        }
    }
    sheet
}
