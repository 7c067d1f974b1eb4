//! Raster images for the page: palette images encoded as PNG, inlined as a base64 data URI.

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;

/// An image of at most 256 colours (a palette and one index a pixel), rows top to bottom:
/// a third of the bytes of RGB, and it compresses better.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PaletteImage {
    pub width: u32,
    pub height: u32,
    /// The colours, at most 256.
    pub palette: Vec<[u8; 3]>,
    /// `width · height` palette indices, row-major.
    pub pixels: Vec<u8>,
}

impl PaletteImage {
    /// A `width × height` image of palette colour 0.
    pub fn new(width: u32, height: u32, palette: Vec<[u8; 3]>) -> Self {
        debug_assert!(!palette.is_empty() && palette.len() <= 256);
        Self { width, height, palette, pixels: vec![0; width as usize * height as usize] }
    }

    /// Sets pixel (`column`, `row`), row 0 at the top, to palette colour `index`; pixels outside
    /// the image are ignored.
    pub fn set(&mut self, column: usize, row: usize, index: u8) {
        if column < self.width as usize && row < self.height as usize {
            self.pixels[row * self.width as usize + column] = index;
        }
    }

    /// The image as a `data:image/png;base64,...` URI, or `None` when the encoder refuses it
    /// (an empty image, a bad palette).
    pub fn data_uri(&self) -> Option<String> {
        let png = self.encode().ok()?;
        Some(format!("data:image/png;base64,{}", STANDARD.encode(&png)))
    }

    fn encode(&self) -> Result<Vec<u8>, png::EncodingError> {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, self.width, self.height);
        encoder.set_color(png::ColorType::Indexed);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_palette(self.palette.concat());
        encoder.set_compression(png::Compression::Balanced);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&self.pixels)?;
        writer.finish()?;
        Ok(bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_has_its_signature_and_empty_images_are_refused() {
        let mut image = PaletteImage::new(3, 2, vec![[255, 255, 255], [0, 0, 0]]);
        image.set(2, 1, 1);
        image.set(7, 7, 1); // outside: ignored
        let uri = image.data_uri().expect("a 3 × 2 image encodes");
        // The PNG signature \x89PNG\r\n\x1a\n encodes as iVBORw0KGgo.
        assert!(uri.starts_with("data:image/png;base64,iVBORw0KGgo"), "{uri}");
        assert_eq!(PaletteImage::new(0, 0, vec![[0, 0, 0]]).data_uri(), None);
    }
}
