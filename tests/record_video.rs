//! `quadcl record --format mp4` and its kin: a video of the shipped base read back with ffprobe
//! has one frame per control step at the asked size, several tasks stand side by side, a
//! missing ffmpeg is a clear error that leaves no file, and `quadcl eval` names the learned task
//! whose network acts. Tests that encode need ffmpeg on PATH: without it they say so and pass,
//! unless QUADCL_REQUIRE_FFMPEG is set (`.ci/run` sets it and installs ffmpeg).

mod record_common;

use quadcl::record::{record_video, VideoSize};
use record_common::{base, options};
use std::process::Command;

fn have_ffmpeg() -> bool {
    let found = Command::new("ffprobe").arg("-version").output().is_ok_and(|o| o.status.success())
        && Command::new("ffmpeg").arg("-version").output().is_ok_and(|o| o.status.success());
    assert!(
        found || std::env::var_os("QUADCL_REQUIRE_FFMPEG").is_none(),
        "QUADCL_REQUIRE_FFMPEG: no ffmpeg/ffprobe on PATH"
    );
    if !found {
        eprintln!("skipped: no ffmpeg/ffprobe on PATH");
    }
    found
}

/// (codec, width, height, frames) of a video's first stream, as ffprobe counts them.
fn probe(file: &std::path::Path) -> (String, usize, usize, usize) {
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries"])
        .args(["stream=codec_name,width,height,nb_read_frames", "-of", "csv=p=0"])
        .arg(file)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let v: Vec<&str> = text.trim().split(',').collect();
    (v[0].to_string(), v[1].parse().unwrap(), v[2].parse().unwrap(), v[3].parse().unwrap())
}

#[test]
fn a_video_has_a_frame_per_control_step_at_its_size_and_tasks_side_by_side() {
    if !have_ffmpeg() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("walk.mp4");
    let summary =
        record_video(&base(), &["none".into()], &one, VideoSize { width: 160, height: 120 }, &options(1.0)).unwrap();
    assert_eq!(summary.control_steps, 50);
    assert!(summary.bytes > 1000 && summary.bytes == std::fs::metadata(&one).unwrap().len());
    assert_eq!(probe(&one), ("h264".to_string(), 160, 120, 50));
    let two = tmp.path().join("sub/side.mp4");
    let tasks = ["none".to_string(), "crash:FL".to_string()];
    record_video(&base(), &tasks, &two, VideoSize { width: 160, height: 120 }, &options(0.5)).unwrap();
    assert_eq!(probe(&two), ("h264".to_string(), 320, 120, 25));
    // Nothing but the two videos is left behind (no partial file).
    let left: Vec<_> = walkdir(tmp.path());
    assert_eq!(left.len(), 2, "{left:?}");
}

fn walkdir(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files.extend(walkdir(&p));
        } else {
            files.push(p);
        }
    }
    files
}

#[test]
fn without_ffmpeg_a_video_is_an_error_saying_how_to_install_it_and_leaves_no_file() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("walk.mp4");
    let status = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["record", "--policy", base().to_str().unwrap(), "--seconds", "0.2", "--format", "mp4", "--out"])
        .arg(tmp.path().join("walk"))
        .env("QUADCL_FFMPEG", tmp.path().join("no-ffmpeg-here"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&status.stderr);
    assert!(!status.status.success());
    assert!(err.contains("walk.mp4") && err.contains("ffmpeg") && err.contains("apt-get install ffmpeg"), "{err}");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0, "no file left");
    assert!(!out.exists());
}

#[test]
fn a_format_that_disagrees_with_the_files_extension_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["record", "--policy", base().to_str().unwrap(), "--format", "mp4", "--out"])
        .arg(tmp.path().join("walk.mcap"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains(".mcap") && err.contains("--format is mp4"), "{err}");
    // Several tasks side by side are for a video only.
    let out = Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["record", "--policy", base().to_str().unwrap(), "--task", "none,crash:FL", "--out"])
        .arg(tmp.path().join("walk.mcap"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("video"), "{err}");
}

#[test]
fn eval_names_the_learned_task_whose_network_acts() {
    let adapter = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("policies/sequence-a1-adapter/checkpoints/step-03-crash_FR");
    let recalls = |task: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_quadcl"))
            .args(["eval", "--policy", adapter.to_str().unwrap(), "--task", task, "--episodes", "2", "--json"])
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v["recalls"].as_str().unwrap().to_string()
    };
    assert_eq!(recalls("crash:FL"), "crash:FL");
    assert_eq!(recalls("invert:RR"), "crash:FR", "a task never learned runs with the last learned task's network");
}

/// `quadcl run` of the smoke scene with `[run] videos = true` into `out`, with `ffmpeg` as the encoder.
fn smoke_with_videos(out: &std::path::Path, ffmpeg: &std::ffi::OsStr) -> std::process::Output {
    let smoke =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/smoke.toml")).unwrap();
    let file = out.with_extension("toml");
    std::fs::write(&file, smoke.replacen("[[task]]", "[run]\nvideos = true\n\n[[task]]", 1)).unwrap();
    Command::new(env!("CARGO_BIN_EXE_quadcl"))
        .args(["run", "--config", file.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .env("QUADCL_FFMPEG", ffmpeg)
        .output()
        .unwrap()
}

#[test]
fn a_run_with_videos_films_each_task_it_learns_and_without_ffmpeg_only_warns() {
    let tmp = tempfile::tempdir().unwrap();
    // Without an encoder the run still ends well, and its log says why there is no video.
    let out = tmp.path().join("no-ffmpeg");
    let run = smoke_with_videos(&out, tmp.path().join("no-ffmpeg-here").as_os_str());
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let log = std::fs::read_to_string(out.join("log.txt")).unwrap();
    assert_eq!(log.matches("warning: no video of step").count(), 3, "{log}");
    assert!(!out.join("videos").exists() || std::fs::read_dir(out.join("videos")).unwrap().count() == 0);
    if !have_ffmpeg() {
        return;
    }
    let out = tmp.path().join("films");
    let run = smoke_with_videos(&out, std::ffi::OsStr::new("ffmpeg"));
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let mut videos: Vec<String> = std::fs::read_dir(out.join("videos"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    videos.sort();
    assert_eq!(videos.len(), 3, "one video per task: {videos:?}");
    for v in &videos {
        let (codec, w, h, frames) = probe(&out.join("videos").join(v));
        assert_eq!((codec.as_str(), w, h, frames), ("h264", 320, 240, 300), "{v}: 6 s at 50 fps");
    }
}

#[test]
fn a_filmstrip_has_a_row_of_pictures_per_task_with_the_perturbed_leg_in_red_on_its_row_only() {
    use quadcl::record::{filmstrip, Filmstrip};
    let strip = Filmstrip { frames: 3, size: VideoSize { width: 80, height: 60 }, ..Filmstrip::default() };
    let picture = filmstrip(&base(), &["none".to_string(), "crash:FL".to_string()], &strip).unwrap();
    assert_eq!((picture.width, picture.height), (240, 120));
    let red = |y0: usize| {
        (y0..y0 + 60)
            .flat_map(|y| (0..240).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let [r, g, b] = picture.pixel(x, y);
                r > 150 && g < 110 && b < 110
            })
            .count()
    };
    assert_eq!(red(0), 0, "none: no leg perturbed");
    assert!(red(60) > 10, "crash:FL: its front-left leg in red");
    // Three different instants of the gait.
    let tile = |i: usize| {
        (0..60)
            .flat_map(|y| picture.rgb[3 * (y * 240 + 80 * i)..3 * (y * 240 + 80 * i + 80)].to_vec())
            .collect::<Vec<u8>>()
    };
    assert!(tile(0) != tile(1) && tile(1) != tile(2));
}
