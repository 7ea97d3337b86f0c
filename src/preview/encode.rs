//! Encode stage: the sheet as PNG, the frames as an animated GIF or APNG (`png` and `gif`
//! crates; no time stamps or other varying chunks, so the bytes depend only on the pixels).

use super::raster::Picture;
use anyhow::{Context, Result};

/// PNG bytes of `p` (8-bit RGB).
pub fn png(p: &Picture) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    {
        let mut e = png::Encoder::new(&mut out, p.width as u32, p.height as u32);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        let mut w = e.write_header().context("PNG header")?;
        w.write_image_data(&p.rgb).context("PNG data")?;
        w.finish().context("PNG end")?;
    }
    Ok(out)
}

/// Animated PNG of `frames` (equal sizes), each shown for its delay in seconds, looping.
pub fn apng(frames: &[(Picture, f64)]) -> Result<Vec<u8>> {
    let first = &frames.first().context("no frames to animate")?.0;
    let mut out = Vec::new();
    {
        let mut e = png::Encoder::new(&mut out, first.width as u32, first.height as u32);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        e.set_animated(frames.len() as u32, 0).context("APNG")?;
        let mut w = e.write_header().context("APNG header")?;
        for (p, delay) in frames {
            let ms = (delay * 1000.0).round().clamp(10.0, 65_535.0) as u16;
            w.set_frame_delay(ms, 1000).context("APNG delay")?;
            w.write_image_data(&p.rgb).context("APNG frame")?;
        }
        w.finish().context("APNG end")?;
    }
    Ok(out)
}

/// Animated GIF of `frames` (equal sizes), each shown for its delay in seconds (GIF counts in
/// hundredths, at least 2), looping; each frame's palette from NeuQuant (deterministic).
pub fn gif(frames: &[(Picture, f64)]) -> Result<Vec<u8>> {
    let first = &frames.first().context("no frames to animate")?.0;
    let (w, h) = (first.width as u16, first.height as u16);
    let mut out = Vec::new();
    {
        let mut e = gif::Encoder::new(&mut out, w, h, &[]).context("GIF header")?;
        e.set_repeat(gif::Repeat::Infinite).context("GIF loop")?;
        for (p, delay) in frames {
            let mut f = gif::Frame::from_rgb_speed(w, h, &p.rgb, 10);
            f.delay = (delay * 100.0).round().clamp(2.0, 65_535.0) as u16;
            e.write_frame(&f).context("GIF frame")?;
        }
    }
    Ok(out)
}
