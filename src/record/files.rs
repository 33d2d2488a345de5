//! The files of a recording: frame paths, which frames a resumed run keeps (complete, and made
//! of what would make them now), the run over a frame range with atomic writes, and the video
//! made from the frames with the system ffmpeg.

use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::output::{Format, OutputOptions, Provenance};

use super::{MAX_FRAMES_PER_RUN, RecordError, Recorder, Renderer};

/// `dir/frame_00042.png`.
pub fn frame_path(dir: &Path, frame: u32) -> PathBuf {
    frame_path_as(dir, frame, Format::Png)
}

/// `dir/frame_00042.png` or `.exr`, by `format`.
pub fn frame_path_as(dir: &Path, frame: u32, format: Format) -> PathBuf {
    dir.join(format!("frame_{frame:05}.{}", format.extension()))
}

/// Whether `path` is a PNG (or by its extension an EXR) of `width`×`height` that decodes
/// completely.
pub fn is_complete_frame(path: &Path, width: u32, height: u32) -> bool {
    if Format::for_path(path) == Some(Format::Exr) {
        return crate::output::exr::is_complete(path, width, height);
    }
    match image::open(path) {
        Ok(img) => img.width() == width && img.height() == height,
        Err(_) => false,
    }
}

/// What a recording run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordReport {
    pub rendered: Vec<u32>,
    /// Complete frames left as they were (with `resume`).
    pub skipped: Vec<u32>,
    /// Rendered 8-bit frames in which no point landed (all background).
    pub empty: Vec<u32>,
}

/// The frames of `frames` that still need rendering (all of them unless `resume`).
pub fn frames_to_render(rec: &Recorder, dir: &Path, frames: Range<u32>, resume: bool) -> Vec<u32> {
    frames_to_render_as(rec, dir, frames, resume, Format::Png)
}

/// [`frames_to_render`] for frames in `format`. A PNG frame is kept only when it is complete
/// and was made of what would make it now: the fingerprint of the scene and settings in its
/// text chunks ([`Recorder::provenance`]) equals this recording's, so a resumed sequence never
/// mixes settings. (EXR frames carry no scene; they are checked for completeness only.)
pub fn frames_to_render_as(rec: &Recorder, dir: &Path, frames: Range<u32>, resume: bool, format: Format) -> Vec<u32> {
    let s = rec.settings();
    let keep = |k: u32| {
        let path = frame_path_as(dir, k, format);
        is_complete_frame(&path, s.width, s.height) && (format == Format::Exr || made_by(&path, &rec.provenance(k)))
    };
    frames.filter(|&k| !(resume && keep(k))).collect()
}

/// The PNG at `path` carries `provenance`'s fingerprint (a frame of older nlifs, with no scene
/// inside, does not).
fn made_by(path: &Path, provenance: &Provenance) -> bool {
    crate::output::png::scene_from_png(path).is_ok_and(|found| found.fingerprint() == provenance.fingerprint())
}

/// Renders frames `frames` into `dir`. With `resume`, frames already complete are kept; any
/// other file at a frame's path is replaced. `progress(done, total)` follows each written frame.
pub fn record(
    rec: &Recorder,
    dir: &Path,
    frames: Range<u32>,
    resume: bool,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<RecordReport, RecordError> {
    record_as(rec, dir, frames, resume, &OutputOptions::default(), progress)
}

/// [`record`] with frames written as `options` say (PNG frames carry the scene).
pub fn record_as(
    rec: &Recorder,
    dir: &Path,
    frames: Range<u32>,
    resume: bool,
    options: &OutputOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<RecordReport, RecordError> {
    let count = rec.frame_count();
    if frames.start >= frames.end || frames.end > count {
        return Err(RecordError::FrameRange { start: frames.start, end: frames.end, count });
    }
    if frames.len() > MAX_FRAMES_PER_RUN as usize {
        return Err(RecordError::TooManyFrames { start: frames.start, end: frames.end });
    }
    let todo = frames_to_render_as(rec, dir, frames.clone(), resume, options.format);
    if resume {
        remove_stale_temp_files(dir, frames.clone(), options.format.extension());
    }
    // `todo` is in increasing order, so a binary search keeps this linear-logarithmic.
    let skipped = frames.filter(|k| todo.binary_search(k).is_err()).collect();
    let mut empty = Vec::new();
    for (n, &k) in todo.iter().enumerate() {
        let path = frame_path_as(dir, k, options.format);
        let provenance = rec.provenance(k);
        if options.is_plain_png() {
            let image = rec.frame(k)?;
            let background = rec.scene.render_at(rec.time_of(k)).background;
            // A traced frame shows its ground plane even where the attractor is out of view.
            let chaos = rec.settings().renderer == Renderer::Chaos;
            if chaos && crate::scene::warnings::covered_pixels(&image, background) == 0 {
                empty.push(k);
            }
            crate::output::png::save_rgb8(&path, &image, Some(&provenance))?;
        } else {
            crate::output::write_image(&path, &rec.frame_layers(k)?, options, Some(&provenance))?;
        }
        progress(n + 1, todo.len());
    }
    Ok(RecordReport { rendered: todo, skipped, empty })
}

/// Removes temporary frame files (`.frame_00042.png.<pid>.tmp`) that a killed run left for
/// frames in `frames`. Chunks of a job array own disjoint frame ranges, so this never touches
/// a file another running chunk is writing.
fn remove_stale_temp_files(dir: &Path, frames: Range<u32>, extension: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.filter_map(|e| e.ok()) {
        let name = entry.file_name().to_string_lossy().into_owned();
        let frame = name
            .strip_prefix(".frame_")
            .filter(|_| name.ends_with(".tmp"))
            .and_then(|rest| rest.split_once(&format!(".{extension}.")))
            .and_then(|(digits, _)| digits.parse::<u32>().ok());
        if frame.is_some_and(|k| frames.contains(&k)) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Whether ffmpeg can be run.
pub fn ffmpeg_available() -> bool {
    std::process::Command::new("ffmpeg")
        .arg("-version")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok()
}

/// Encodes frames `frames` of `dir` into the video `out` with the system ffmpeg (H.264 in
/// .mp4/.mov/.mkv, ffmpeg's default codec for other containers), written atomically.
pub fn encode_video(dir: &Path, frames: Range<u32>, fps: f64, out: &Path) -> Result<(), RecordError> {
    if !ffmpeg_available() {
        return Err(RecordError::NoFfmpeg { dir: dir.display().to_string() });
    }
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("mp4").to_ascii_lowercase();
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    // The temporary file keeps the extension: ffmpeg picks the container from it.
    let tmp = out.with_file_name(format!(".{stem}.{}.tmp.{ext}", std::process::id()));
    if let Some(parent) = out.parent()
        && !parent.as_os_str().is_empty()
    {
        std::fs::create_dir_all(parent).map_err(RecordError::FfmpegIo)?;
    }
    let mut cmd = std::process::Command::new("ffmpeg");
    cmd.args(["-y", "-loglevel", "error", "-framerate"])
        .arg(format!("{fps}"))
        .arg("-start_number")
        .arg(frames.start.to_string())
        .arg("-i")
        .arg(dir.join("frame_%05d.png"))
        .arg("-frames:v")
        .arg((frames.end - frames.start).to_string())
        // H.264 in 4:2:0 needs even dimensions.
        .args(["-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"]);
    if matches!(ext.as_str(), "mp4" | "mov" | "mkv") {
        cmd.args(["-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18"]);
    }
    let output = cmd.arg(&tmp).output().map_err(RecordError::FfmpegIo)?;
    if !output.status.success() {
        let _ = std::fs::remove_file(&tmp);
        return Err(RecordError::Ffmpeg {
            status: output.status.to_string(),
            stderr: String::from_utf8_lossy(&output.stderr).trim().to_string(),
        });
    }
    std::fs::rename(&tmp, out).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        RecordError::FfmpegIo(e)
    })
}

/// Parses a frame range `A..B` (half-open).
pub fn parse_frame_range(s: &str) -> Result<Range<u32>, String> {
    let (a, b) = s.split_once("..").ok_or_else(|| format!("`{s}` is not a frame range; write A..B, e.g. 0..48"))?;
    let a: u32 = a.trim().parse().map_err(|_| format!("`{a}` in `{s}` is not a frame number"))?;
    let b: u32 = b.trim().parse().map_err(|_| format!("`{b}` in `{s}` is not a frame number"))?;
    if b <= a {
        return Err(format!("frame range `{s}` is empty; the end is exclusive"));
    }
    Ok(a..b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_parse() {
        assert_eq!(parse_frame_range("0..50"), Ok(0..50));
        assert!(parse_frame_range("5..5").is_err());
        assert!(parse_frame_range("5").is_err());
        assert!(parse_frame_range("a..3").is_err());
    }
}
