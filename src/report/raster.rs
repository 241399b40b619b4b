//! SVG → PNG with `resvg`, using only the bundled DejaVu Sans (no system fonts, no files read
//! at run time), and text measurement from the same font for layout.

use std::io;
use std::sync::{Arc, OnceLock};

use resvg::{tiny_skia, usvg};
use skrifa::MetadataProvider;

/// DejaVu Sans (Bitstream Vera licence, see `assets/fonts/DejaVuSans-LICENSE.txt`).
pub(crate) static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Family name the SVG files use; the font database maps it (and `sans-serif`) to the bundled
/// font.
pub(crate) const FONT_FAMILY: &str = "DejaVu Sans";

fn fontdb() -> Arc<usvg::fontdb::Database> {
    static DB: OnceLock<Arc<usvg::fontdb::Database>> = OnceLock::new();
    DB.get_or_init(|| {
        let mut db = usvg::fontdb::Database::new();
        db.load_font_source(usvg::fontdb::Source::Binary(Arc::new(DEJAVU_SANS)));
        db.set_sans_serif_family(FONT_FAMILY);
        Arc::new(db)
    })
    .clone()
}

/// Advance widths of the bundled font for `size_px = 1`, cached per character code below 0x3000
/// (enough for Latin, Greek, symbols and arrows); other characters count as 0.6 em.
fn advance_em(c: char) -> f64 {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    let table = TABLE.get_or_init(|| {
        let Ok(font) = skrifa::FontRef::new(DEJAVU_SANS) else {
            return Vec::new();
        };
        let charmap = font.charmap();
        let metrics = font.glyph_metrics(
            skrifa::instance::Size::new(1.0),
            skrifa::instance::LocationRef::default(),
        );
        (0u32..0x3000)
            .map(|u| {
                char::from_u32(u)
                    .and_then(|ch| charmap.map(ch))
                    .and_then(|g| metrics.advance_width(g))
                    .unwrap_or(0.6)
            })
            .collect()
    });
    table.get(c as usize).map_or(0.6, |&w| f64::from(w))
}

/// Width in px of `text` set in the bundled font at `size_px` (sum of advances, no kerning).
pub(crate) fn text_width_px(text: &str, size_px: f64) -> f64 {
    text.chars().map(advance_em).sum::<f64>() * size_px
}

/// Rasterises an SVG document to PNG bytes at its own size (1 SVG px = 1 pixel), text set in
/// the bundled DejaVu Sans. Deterministic: the same SVG gives the same bytes.
///
/// Errors: `InvalidData` if the SVG does not parse or has a zero size.
pub fn svg_to_png(svg: &str) -> io::Result<Vec<u8>> {
    let opt = usvg::Options {
        font_family: FONT_FAMILY.to_owned(),
        fontdb: fontdb(),
        ..usvg::Options::default()
    };
    let bad = |m: String| io::Error::new(io::ErrorKind::InvalidData, m);
    let tree = usvg::Tree::from_str(svg, &opt).map_err(|e| bad(format!("SVG parse: {e}")))?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| bad(format!("SVG has an empty size {size:?}")))?;
    resvg::render(
        &tree,
        tiny_skia::Transform::identity(),
        &mut pixmap.as_mut(),
    );
    pixmap
        .encode_png()
        .map_err(|e| bad(format!("PNG encode: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference: DejaVu Sans metrics (2048 units/em): 'M' advance 1767 units = 0.8628 em,
    /// space 651 units = 0.3179 em; read from the font's cmap + hmtx tables with an independent
    /// 40-line Python parser of the TrueType file (unitsPerEm 2048 from `head`).
    #[test]
    fn val_text_width_matches_dejavu_hmtx() {
        assert!((text_width_px("M", 1.0) - 1767.0 / 2048.0).abs() < 1e-4);
        assert!((text_width_px(" ", 1.0) - 651.0 / 2048.0).abs() < 1e-4);
        assert!((text_width_px("MM", 12.0) - 2.0 * 12.0 * 1767.0 / 2048.0).abs() < 1e-3);
    }
}
