//! Image and file output. Every file is written to a temporary file in the target folder and
//! renamed into place, so a failed or interrupted write never leaves a partial file.

use std::io::Write;
use std::path::{Path, PathBuf};

use convshadow_common::model::display::{DisplayMap, linear_to_srgb8, srgb8_to_linear};

/// An output error: names the file and what went wrong.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct OutputError {
    /// The target file.
    pub path: String,
    /// What went wrong.
    pub message: String,
}

fn out_err(path: &Path, message: impl Into<String>) -> OutputError {
    OutputError {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// The temporary file used while writing `path` (same folder, so the rename is atomic).
pub fn temp_path_for(path: &Path) -> PathBuf {
    let name = path.file_name().map_or_else(
        || "output".to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let pid = std::process::id();
    let long = format!(".{name}.{pid}.partial");
    // File names are at most 255 bytes: a long name gets a short one (a hash of the name).
    if long.len() <= 255 {
        return path.with_file_name(long);
    }
    let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    path.with_file_name(format!(".cs-{hash:016x}.{pid}.partial"))
}

/// The longest file name (one path component) Linux file systems take, in bytes (`NAME_MAX`).
pub const MAX_NAME_BYTES: usize = 255;

/// Checks that `path` can be written: [`check_target`] (the name and what is there now) and
/// [`check_folder`] (its folder exists and takes a new file), so a render is refused before it
/// starts, not after.
pub fn check_writable(path: &Path) -> Result<(), OutputError> {
    check_target(path)?;
    check_folder(path)
}

/// The folder `path` is written in (`.` for a bare name).
pub fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Checks `path` itself, without touching its folder: a file name (not ending in `/`, `.` or
/// `..`) of at most [`MAX_NAME_BYTES`] bytes, not an existing folder, device, FIFO or socket
/// (never replaced by a regular file). The checks a rename into place would otherwise fail only
/// after the work.
pub fn check_target(path: &Path) -> Result<(), OutputError> {
    use std::os::unix::ffi::OsStrExt;
    let bytes = path.as_os_str().as_bytes();
    let last = bytes.rsplit(|&b| b == b'/').next().unwrap_or_default();
    if path.is_dir() {
        return Err(out_err(path, "is a folder; expected a file path"));
    }
    if matches!(last, b"" | b"." | b"..") {
        return Err(out_err(
            path,
            "names a folder (it ends in `/`, `.` or `..`); expected a file path",
        ));
    }
    if last.len() > MAX_NAME_BYTES {
        return Err(out_err(
            path,
            format!(
                "the file name is {} bytes long; file systems take at most {MAX_NAME_BYTES}",
                last.len()
            ),
        ));
    }
    // A device, FIFO or socket is never replaced by a regular file.
    if let Ok(meta) = std::fs::metadata(path)
        && !meta.is_file()
    {
        return Err(out_err(
            path,
            "exists and is not a regular file (a device, FIFO or socket); refusing to replace it",
        ));
    }
    Ok(())
}

/// Checks that `path`'s folder exists, is a folder, and takes a new file (probed by creating
/// and removing `path`'s temporary file).
pub fn check_folder(path: &Path) -> Result<(), OutputError> {
    let dir = folder_of(path);
    if !dir.is_dir() {
        let why = if dir.exists() {
            "is not a folder"
        } else {
            "does not exist"
        };
        return Err(out_err(path, format!("folder {} {why}", dir.display())));
    }
    let tmp = temp_path_for(path);
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&tmp);
        }
        // Left by an earlier write of this process: creatable, then.
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => {
            return Err(out_err(
                path,
                format!("cannot create a file in folder {}: {e}", dir.display()),
            ));
        }
    }
    Ok(())
}

/// Writes bytes produced by `fill` atomically to `path`.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), OutputError> {
    check_writable(path)?;
    let tmp = temp_path_for(path);
    let result = (|| -> std::io::Result<()> {
        let file = std::fs::File::create(&tmp)?;
        let mut w = std::io::BufWriter::new(file);
        fill(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(out_err(path, format!("cannot write: {e}")));
    }
    Ok(())
}

/// One channel of an EXR output beside `R`, `G`, `B` ([`RgbImage::save_exr`]).
#[derive(Clone, Copy, Debug)]
pub struct ExrChannel<'a> {
    /// The channel's name, as OpenEXR tools show it: `A`, `Z`, `light0.R`, …
    pub name: &'a str,
    /// `width·height` values, row-major.
    pub data: &'a [f32],
}

/// A linear RGB float image, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width·height·3` linear values.
    pub data: Vec<f32>,
}

impl RgbImage {
    /// The 8-bit sRGB encoding of the image.
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.data.iter().map(|&v| linear_to_srgb8(v)).collect()
    }

    /// Writes the image by extension: `.png` (sRGB 8-bit, clamped) or `.exr` (linear float).
    pub fn save(&self, path: &Path) -> Result<(), OutputError> {
        self.save_mapped(path, &DisplayMap::CLAMP)
    }

    /// Writes the image by extension: `.png` through `map` (exposure, tone curve, sRGB 8-bit) or
    /// `.exr` (linear float, `map` ignored).
    pub fn save_mapped(&self, path: &Path, map: &DisplayMap) -> Result<(), OutputError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "png" => {
                let buf =
                    image::RgbImage::from_raw(self.width, self.height, map.to_srgb8(&self.data))
                        .ok_or_else(|| out_err(path, "image buffer has the wrong size"))?;
                encode(
                    path,
                    image::DynamicImage::ImageRgb8(buf),
                    image::ImageFormat::Png,
                )
            }
            "exr" => self.save_exr(path, &[]),
            _ => Err(out_err(
                path,
                "unknown image extension; expected .png or .exr",
            )),
        }
    }

    /// Writes the image as an EXR file: the channels `R`, `G`, `B` (f32, the image's values bit
    /// for bit) and `extra` (f32, each `width·height` values, row-major), in one part, scan
    /// lines ZIP-compressed (lossless), channels sorted by name as the format asks. Channel
    /// names follow OpenEXR's conventions: `A` (alpha), `Z` (depth), `layer.R` for a layer's
    /// red. A name that is empty, repeated or one of `R`, `G`, `B`, or data of the wrong length,
    /// is an error; nothing is written then.
    pub fn save_exr(&self, path: &Path, extra: &[ExrChannel<'_>]) -> Result<(), OutputError> {
        use exr::prelude::{
            AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes,
            WritableImage,
        };
        let (w, h) = (self.width as usize, self.height as usize);
        if self.data.len() != w * h * 3 {
            return Err(out_err(path, "image buffer has the wrong size"));
        }
        let mut names: Vec<&str> = vec!["R", "G", "B"];
        for c in extra {
            if c.name.is_empty() || names.contains(&c.name) {
                return Err(out_err(
                    path,
                    format!("EXR channel name {:?} is empty or repeated", c.name),
                ));
            }
            if c.data.len() != w * h {
                return Err(out_err(
                    path,
                    format!(
                        "EXR channel {} has {} values, expected {}",
                        c.name,
                        c.data.len(),
                        w * h
                    ),
                ));
            }
            names.push(c.name);
        }
        let plane =
            |k: usize| -> Vec<f32> { self.data.iter().skip(k).step_by(3).copied().collect() };
        let mut channels: Vec<AnyChannel<FlatSamples>> = ["R", "G", "B"]
            .iter()
            .enumerate()
            .map(|(k, name)| AnyChannel::new(*name, FlatSamples::F32(plane(k))))
            .collect();
        channels.extend(extra.iter().map(|c| {
            let mut channel = AnyChannel::new(c.name, FlatSamples::F32(c.data.to_vec()));
            // `pLinear` (a hint to lossy compressions only): the `exr` crate guesses it from
            // the whole name, so `light0.R` would get it; a layer's channel gets its base
            // name's (`R`: not linear), as alpha keeps its own.
            channel.quantize_linearly = c.name.rsplit('.').next() == Some("A");
            channel
        }));
        let layer = Layer::new(
            (w, h),
            LayerAttributes::default(),
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(channels.into()),
        );
        let mut bytes = std::io::Cursor::new(Vec::new());
        Image::from_layer(layer)
            .write()
            .to_buffered(&mut bytes)
            .map_err(|e| out_err(path, format!("cannot encode: {e}")))?;
        write_atomically(path, |out| out.write_all(bytes.get_ref()))
    }

    /// Reads a PNG (decoded from sRGB to linear) or an EXR (linear).
    pub fn load(path: &Path) -> Result<RgbImage, OutputError> {
        let img =
            image::open(path).map_err(|e| out_err(path, format!("cannot read image: {e}")))?;
        let is_float = matches!(
            img.color(),
            image::ColorType::Rgb32F | image::ColorType::Rgba32F
        );
        let (width, height) = (img.width(), img.height());
        let data = if is_float {
            img.to_rgb32f().into_raw()
        } else {
            img.to_rgb8()
                .into_raw()
                .into_iter()
                .map(srgb8_to_linear)
                .collect()
        };
        Ok(RgbImage {
            width,
            height,
            data,
        })
    }
}

/// Writes an 8-bit grey image as PNG.
pub fn save_gray_png(
    path: &Path,
    width: u32,
    height: u32,
    data: Vec<u8>,
) -> Result<(), OutputError> {
    let buf = image::GrayImage::from_raw(width, height, data)
        .ok_or_else(|| out_err(path, "image buffer has the wrong size"))?;
    encode(
        path,
        image::DynamicImage::ImageLuma8(buf),
        image::ImageFormat::Png,
    )
}

/// Writes an 8-bit RGB image as PNG (atomically, like every output).
pub fn save_rgb8_png(
    path: &Path,
    width: u32,
    height: u32,
    data: Vec<u8>,
) -> Result<(), OutputError> {
    let buf = image::RgbImage::from_raw(width, height, data)
        .ok_or_else(|| out_err(path, "image buffer has the wrong size"))?;
    encode(
        path,
        image::DynamicImage::ImageRgb8(buf),
        image::ImageFormat::Png,
    )
}

fn encode(
    path: &Path,
    img: image::DynamicImage,
    format: image::ImageFormat,
) -> Result<(), OutputError> {
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), format)
        .map_err(|e| out_err(path, format!("cannot encode: {e}")))?;
    write_atomically(path, |w| w.write_all(&bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_every_8bit_value() {
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(v)), v);
        }
        assert_eq!(linear_to_srgb8(-1.0), 0);
        assert_eq!(linear_to_srgb8(2.0), 255);
    }

    #[test]
    fn exr_extra_channels_are_written_bit_for_bit_and_rgb_reads_back_unchanged() {
        use exr::prelude::{FlatSamples, read_all_flat_layers_from_file};
        let dir = std::env::temp_dir().join(format!("convshadow-io-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // Awkward values: a subnormal, −0, a large value, and +inf in Z (no hit).
        let data: Vec<f32> = (0..18)
            .map(|i| match i {
                4 => f32::from_bits(1),
                7 => -0.0,
                11 => 3.0e38,
                _ => i as f32 / 17.0,
            })
            .collect();
        let img = RgbImage {
            width: 3,
            height: 2,
            data,
        };
        let alpha = [0.0, 0.25, 1.0, 0.5, 0.75, 1.0];
        let z = [1.5, f32::INFINITY, -2.0, 0.0, 7.25, f32::INFINITY];
        let red = [0.125; 6];
        let extra = [
            ExrChannel {
                name: "A",
                data: &alpha,
            },
            ExrChannel {
                name: "Z",
                data: &z,
            },
            ExrChannel {
                name: "light0.R",
                data: &red,
            },
        ];
        let path = dir.join("layers.exr");
        img.save_exr(&path, &extra).unwrap();
        let read = read_all_flat_layers_from_file(&path).unwrap();
        assert_eq!(read.layer_data.len(), 1, "one part");
        let channels = &read.layer_data[0].channel_data.list;
        let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
        assert_eq!(names, ["A", "B", "G", "R", "Z", "light0.R"]);
        let bits = |name: &str| -> Vec<u32> {
            let c = channels
                .iter()
                .find(|c| c.name.to_string() == name)
                .unwrap();
            match &c.sample_data {
                FlatSamples::F32(v) => v.iter().map(|v| v.to_bits()).collect(),
                other => panic!("{name}: not f32: {other:?}"),
            }
        };
        for (k, name) in ["R", "G", "B"].iter().enumerate() {
            let want: Vec<u32> = img
                .data
                .iter()
                .skip(k)
                .step_by(3)
                .map(|v| v.to_bits())
                .collect();
            assert_eq!(bits(name), want, "{name}");
        }
        for c in &extra {
            let want: Vec<u32> = c.data.iter().map(|v| v.to_bits()).collect();
            assert_eq!(bits(c.name), want, "{}", c.name);
        }
        // The `image` crate (`RgbImage::load`, `convshadow diff`) reads the RGB bits back.
        let back = RgbImage::load(&path).unwrap();
        let back_bits: Vec<u32> = back.data.iter().map(|v| v.to_bits()).collect();
        let want: Vec<u32> = img.data.iter().map(|v| v.to_bits()).collect();
        assert_eq!(back_bits, want);
        // Bad channels: errors naming the channel, and no file.
        let bad = dir.join("bad.exr");
        for (extra, words) in [
            (
                vec![ExrChannel {
                    name: "G",
                    data: &alpha,
                }],
                "repeated",
            ),
            (
                vec![ExrChannel {
                    name: "",
                    data: &alpha,
                }],
                "empty",
            ),
            (
                vec![ExrChannel {
                    name: "A",
                    data: &alpha[..5],
                }],
                "A has 5 values",
            ),
        ] {
            let e = img.save_exr(&bad, &extra).unwrap_err().to_string();
            assert!(e.contains(words), "{e}");
            assert!(!bad.exists());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn images_round_trip_and_failed_writes_leave_nothing() {
        let dir = std::env::temp_dir().join(format!("convshadow-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let img = RgbImage {
            width: 3,
            height: 2,
            data: (0..18).map(|i| i as f32 / 17.0).collect(),
        };
        let exr = dir.join("a.exr");
        img.save(&exr).unwrap();
        assert_eq!(RgbImage::load(&exr).unwrap(), img);
        let png = dir.join("a.png");
        img.save(&png).unwrap();
        let back = RgbImage::load(&png).unwrap();
        assert_eq!(back.to_srgb8(), img.to_srgb8());
        // A folder as the target, and a missing folder: errors, and no file or temp file left.
        assert!(img.save(&dir).is_err());
        let missing = dir.join("nope/x.png");
        assert!(
            img.save(&missing)
                .unwrap_err()
                .to_string()
                .contains("does not exist")
        );
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left.len(), 2, "{left:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
