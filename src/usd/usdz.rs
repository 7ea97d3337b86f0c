//! `.usdz` packages: an uncompressed zip whose first file is the root layer, every file's data
//! starting on a 64-byte boundary (padding goes in the local header's extra field), as the
//! USDZ specification requires. Timestamps are fixed so output is deterministic.

use anyhow::{bail, Context, Result};
use std::io::{Read, Write};
use std::path::PathBuf;

const ALIGN: u64 = 64;
/// Extra-field id used for alignment padding (the value usd-core itself writes).
const PAD_ID: u16 = 0x1986;
/// 1980-01-01 00:00 in DOS date/time.
const DOS_DATE: u16 = (1 << 5) | 1;

/// Write a package of `files` (name in the archive, file on disk) to `out`.
pub fn write_package(out: &mut dyn Write, files: &[(String, PathBuf)]) -> Result<()> {
    let mut pos: u64 = 0;
    let mut central = Vec::new();
    let put = |out: &mut dyn Write, b: &[u8], pos: &mut u64| -> Result<()> {
        out.write_all(b)?;
        *pos += b.len() as u64;
        Ok(())
    };
    for (name, file) in files {
        let size = std::fs::metadata(file)
            .with_context(|| format!("{}", file.display()))?
            .len();
        if size >= u32::MAX as u64 || pos >= u32::MAX as u64 {
            bail!(
                "{}: the package would pass 4 GiB (zip64 is not written)",
                file.display()
            );
        }
        let mut crc = crc32fast::Hasher::new();
        let mut buf = vec![0u8; 1 << 20];
        let mut f = std::fs::File::open(file)?;
        loop {
            let n = f.read(&mut buf)?;
            if n == 0 {
                break;
            }
            crc.update(&buf[..n]);
        }
        let crc = crc.finalize();
        let header_at = pos;
        let fixed = 30 + name.len() as u64;
        let mut pad = (ALIGN - (pos + fixed) % ALIGN) % ALIGN;
        if pad > 0 && pad < 4 {
            pad += ALIGN;
        }
        let mut h = Vec::new();
        h.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        h.extend_from_slice(&20u16.to_le_bytes()); // version needed
        h.extend_from_slice(&0u16.to_le_bytes()); // flags
        h.extend_from_slice(&0u16.to_le_bytes()); // stored
        h.extend_from_slice(&0u16.to_le_bytes()); // time
        h.extend_from_slice(&DOS_DATE.to_le_bytes());
        h.extend_from_slice(&crc.to_le_bytes());
        h.extend_from_slice(&(size as u32).to_le_bytes());
        h.extend_from_slice(&(size as u32).to_le_bytes());
        h.extend_from_slice(&(name.len() as u16).to_le_bytes());
        h.extend_from_slice(&(pad as u16).to_le_bytes());
        h.extend_from_slice(name.as_bytes());
        if pad > 0 {
            h.extend_from_slice(&PAD_ID.to_le_bytes());
            h.extend_from_slice(&((pad - 4) as u16).to_le_bytes());
            h.resize(h.len() + pad as usize - 4, 0);
        }
        put(out, &h, &mut pos)?;
        debug_assert_eq!(pos % ALIGN, 0);
        let mut f = std::fs::File::open(file)?;
        loop {
            let n = f.read(&mut buf)?;
            if n == 0 {
                break;
            }
            put(out, &buf[..n], &mut pos)?;
        }
        let mut c = Vec::new();
        c.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        c.extend_from_slice(&20u16.to_le_bytes()); // made by
        c.extend_from_slice(&20u16.to_le_bytes()); // needed
        c.extend_from_slice(&0u16.to_le_bytes());
        c.extend_from_slice(&0u16.to_le_bytes());
        c.extend_from_slice(&0u16.to_le_bytes());
        c.extend_from_slice(&DOS_DATE.to_le_bytes());
        c.extend_from_slice(&crc.to_le_bytes());
        c.extend_from_slice(&(size as u32).to_le_bytes());
        c.extend_from_slice(&(size as u32).to_le_bytes());
        c.extend_from_slice(&(name.len() as u16).to_le_bytes());
        // extra length, comment length, disk number, internal attributes (2 bytes each) and
        // external attributes (4 bytes): all zero.
        c.extend_from_slice(&[0u8; 12]);
        c.extend_from_slice(&(header_at as u32).to_le_bytes());
        c.extend_from_slice(name.as_bytes());
        central.push(c);
    }
    let cd_at = pos;
    let mut cd_size = 0u64;
    for c in &central {
        put(out, c, &mut pos)?;
        cd_size += c.len() as u64;
    }
    let mut e = Vec::new();
    e.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    e.extend_from_slice(&0u16.to_le_bytes());
    e.extend_from_slice(&0u16.to_le_bytes());
    e.extend_from_slice(&(central.len() as u16).to_le_bytes());
    e.extend_from_slice(&(central.len() as u16).to_le_bytes());
    e.extend_from_slice(&(cd_size as u32).to_le_bytes());
    e.extend_from_slice(&(cd_at as u32).to_le_bytes());
    e.extend_from_slice(&0u16.to_le_bytes());
    put(out, &e, &mut pos)?;
    Ok(())
}
