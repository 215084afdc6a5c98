//! CPU images: composing views side by side and writing PNG / animated PNG files atomically.

use std::path::Path;

use crate::error::RenderError;

/// An 8-bit sRGB RGBA image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbaImage {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
}

impl RgbaImage {
    /// Wraps `pixels` (`width × height × 4` bytes).
    pub fn new(width: u32, height: u32, pixels: Vec<u8>) -> Self {
        debug_assert_eq!(pixels.len(), width as usize * height as usize * 4);
        Self {
            width,
            height,
            pixels,
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The RGBA bytes, rows top to bottom (`width × height × 4`).
    pub fn pixels(&self) -> &[u8] {
        &self.pixels
    }

    /// The pixel at column `x`, row `y` (from the top).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [
            self.pixels[i],
            self.pixels[i + 1],
            self.pixels[i + 2],
            self.pixels[i + 3],
        ]
    }

    /// Fills the rectangle at `(x, y)` of `width × height` pixels with `color` blended by its
    /// alpha; the parts outside the image are skipped.
    pub fn fill_rect(&mut self, x: i64, y: i64, width: u32, height: u32, color: [u8; 4]) {
        let (x0, y0) = (x.max(0), y.max(0));
        let x1 = (x + width as i64).min(self.width as i64);
        let y1 = (y + height as i64).min(self.height as i64);
        let a = color[3] as u32;
        for py in y0..y1 {
            for px in x0..x1 {
                let i = (py as usize * self.width as usize + px as usize) * 4;
                for (channel, &value) in self.pixels[i..i + 3].iter_mut().zip(&color) {
                    let old = *channel as u32;
                    *channel = ((value as u32 * a + old * (255 - a) + 127) / 255) as u8;
                }
                self.pixels[i + 3] = 255;
            }
        }
    }

    /// `left` and `right` next to each other (same height), with a `gap`-pixel divider.
    pub fn side_by_side(left: &RgbaImage, right: &RgbaImage, gap: u32) -> RgbaImage {
        let height = left.height.max(right.height);
        let width = left.width + gap + right.width;
        let mut pixels = vec![255u8; width as usize * height as usize * 4];
        for y in 0..height as usize {
            let row = &mut pixels[y * width as usize * 4..(y + 1) * width as usize * 4];
            for (image, x0) in [(left, 0usize), (right, (left.width + gap) as usize)] {
                if y < image.height as usize {
                    let src = &image.pixels
                        [y * image.width as usize * 4..(y + 1) * image.width as usize * 4];
                    row[x0 * 4..x0 * 4 + src.len()].copy_from_slice(src);
                }
            }
            for x in left.width as usize..(left.width + gap) as usize {
                row[x * 4..x * 4 + 4].copy_from_slice(&[150, 152, 158, 255]);
            }
        }
        RgbaImage::new(width, height, pixels)
    }

    /// Encodes as PNG.
    pub fn to_png(&self) -> Result<Vec<u8>, png::EncodingError> {
        let mut bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut bytes, self.width, self.height);
            encoder.set_color(png::ColorType::Rgba);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
            let mut writer = encoder.write_header()?;
            writer.write_image_data(&self.pixels)?;
        }
        Ok(bytes)
    }

    /// Writes a PNG file through a temporary file and a rename.
    pub fn write_png(&self, path: &Path) -> Result<(), RenderError> {
        let bytes = self.to_png().map_err(|e| write_error(path, e))?;
        write_file_atomically(path, &bytes)
    }
}

fn write_error(path: &Path, e: impl std::fmt::Display) -> RenderError {
    RenderError::Write {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), RenderError> {
    cagerig::io::atomic::write_atomically(path, |w| w.write_all(bytes))
        .map_err(|e| write_error(path, e.reason()))
}

/// Writes `frames` (all the same size, at least one) as an animated PNG looping forever, each
/// frame shown `delay_ms` milliseconds.
pub fn write_apng(path: &Path, frames: &[RgbaImage], delay_ms: u16) -> Result<(), RenderError> {
    let first = frames
        .first()
        .ok_or_else(|| write_error(path, "an animation needs at least one frame"))?;
    if let Some((k, f)) = frames
        .iter()
        .enumerate()
        .find(|(_, f)| (f.width, f.height) != (first.width, first.height))
    {
        return Err(write_error(
            path,
            format!(
                "frame {k} is {}×{}: expected {}×{} like frame 0",
                f.width, f.height, first.width, first.height
            ),
        ));
    }
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, first.width, first.height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder
            .set_animated(frames.len() as u32, 0)
            .map_err(|e| write_error(path, e))?;
        encoder
            .set_frame_delay(delay_ms, 1000)
            .map_err(|e| write_error(path, e))?;
        let mut writer = encoder.write_header().map_err(|e| write_error(path, e))?;
        for frame in frames {
            writer
                .write_image_data(&frame.pixels)
                .map_err(|e| write_error(path, e))?;
        }
        writer.finish().map_err(|e| write_error(path, e))?;
    }
    write_file_atomically(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solid(width: u32, height: u32, c: [u8; 4]) -> RgbaImage {
        RgbaImage::new(width, height, c.repeat((width * height) as usize))
    }

    #[test]
    fn side_by_side_places_both_images_and_the_divider() {
        let image = RgbaImage::side_by_side(
            &solid(3, 2, [255, 0, 0, 255]),
            &solid(2, 2, [0, 0, 255, 255]),
            1,
        );
        assert_eq!((image.width(), image.height()), (6, 2));
        assert_eq!(image.pixel(2, 1), [255, 0, 0, 255]);
        assert_eq!(image.pixel(3, 0), [150, 152, 158, 255]);
        assert_eq!(image.pixel(5, 1), [0, 0, 255, 255]);
    }

    #[test]
    fn png_round_trips_through_the_decoder() {
        let image = RgbaImage::new(2, 1, vec![1, 2, 3, 255, 250, 128, 0, 255]);
        let bytes = image.to_png().unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut buf).unwrap();
        assert_eq!(buf, image.pixels());
    }

    #[test]
    fn apng_rejects_mismatched_frames_and_writes_every_frame() {
        let dir = std::env::temp_dir().join(format!("cagerig-apng-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("spin.png");
        let frames = [
            solid(4, 4, [10, 20, 30, 255]),
            solid(4, 4, [200, 20, 30, 255]),
        ];
        write_apng(&path, &frames, 40).unwrap();
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let reader = decoder.read_info().unwrap();
        assert_eq!(reader.info().animation_control().unwrap().num_frames, 2);
        let err = write_apng(&path, &[solid(4, 4, [0; 4]), solid(3, 4, [0; 4])], 40).unwrap_err();
        assert!(err.to_string().contains("frame 1 is 3×4"), "{err}");
        assert!(write_apng(&path, &[], 40).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
