//! Shared by the report and figure tests: headless Chromium, PNG decoding and the checks that
//! a screenshot of a report is not blank and shows Table 3.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The browser window, px.
pub const WINDOW: (u32, u32) = (1280, 1600);

/// Colours of the style sheet that the checks look for.
pub const HEADER_BLUE: [u8; 3] = [0xdc, 0xe6, 0xf2];
pub const MISS_RED: [u8; 3] = [0xf6, 0xd5, 0xd5];
pub const PASS_GREEN: [u8; 3] = [0xdd, 0xf1, 0xdf];

/// The browser to use, or `None` when the test is to be skipped.
pub fn chromium() -> Option<PathBuf> {
    if let Some(path) = std::env::var_os("HYSTCOMP_CHROMIUM") {
        return Some(PathBuf::from(path));
    }
    let on_path = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join("chromium"))
            .find(|p| p.is_file())
    });
    let found = on_path.or_else(|| {
        let p = PathBuf::from("/usr/bin/chromium");
        p.is_file().then_some(p)
    });
    if found.is_none() {
        // .ci/run installs chromium: under CI a missing browser fails the test whatever else.
        if std::env::var("HYSTCOMP_SKIP_BROWSER_TESTS").as_deref() == Ok("1")
            && !hystcomp_testkit::under_ci()
        {
            hystcomp_testkit::skip("no chromium found and HYSTCOMP_SKIP_BROWSER_TESTS=1");
            return None;
        }
        panic!(
            "headless Chromium is needed to check the rendered report but was not found \
             (neither `chromium` on PATH nor /usr/bin/chromium). Install it with \
             `apt-get install -y chromium`, point HYSTCOMP_CHROMIUM at a binary, or set \
             HYSTCOMP_SKIP_BROWSER_TESTS=1 to skip this test."
        );
    }
    found
}

/// Runs headless Chromium on `page` with `extra` arguments, stdout to `stdout_file`, killing it
/// after two minutes.
pub fn run_chromium(browser: &Path, extra: &[String], page: &Path, stdout_file: &Path) {
    let profile = tempfile::tempdir().unwrap();
    let stdout = std::fs::File::create(stdout_file).unwrap();
    let stderr_file = stdout_file.with_extension("stderr");
    let stderr = std::fs::File::create(&stderr_file).unwrap();
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
            "--disable-dev-shm-usage",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg(format!("--window-size={},{}", WINDOW.0, WINDOW.1))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .spawn()
        .unwrap_or_else(|e| panic!("could not start {}: {e}", browser.display()));
    let deadline = Instant::now() + Duration::from_secs(120);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("chromium did not finish within 120 s");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let stderr = std::fs::read_to_string(&stderr_file).unwrap_or_default();
    assert!(status.success(), "chromium failed ({status}): {stderr}");
}

/// Screenshots `page` into `dir/screenshot.png` (Chromium's output in `dir/shot.out`) and
/// decodes it: (width, height, RGB pixels).
pub fn screenshot(browser: &Path, page: &Path, dir: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let shot = dir.join("screenshot.png");
    run_chromium(
        browser,
        &[format!("--screenshot={}", shot.display())],
        page,
        &dir.join("shot.out"),
    );
    decode_png(&shot)
}

/// The colour type a PNG file declares in its header.
pub fn png_colour_type(path: &Path) -> png::ColorType {
    let file = std::fs::File::open(path).expect("the PNG exists");
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("a valid PNG header");
    reader.info().color_type
}

/// Decodes a PNG (any colour type, 8 bits per channel after normalising): (width, height,
/// RGB pixels).
pub fn decode_png(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let file = std::fs::File::open(path).expect("chromium wrote the screenshot");
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    assert!(
        channels >= 3,
        "unexpected colour type {:?}",
        info.color_type
    );
    let pixels = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    (info.width, info.height, pixels)
}

pub fn near(p: [u8; 3], c: [u8; 3]) -> bool {
    p.iter().zip(c).all(|(&a, b)| a.abs_diff(b) <= 3)
}

/// Asserts that a screenshot of a report is not blank and shows Table 3: luminance varies, there
/// is dark text, and the table header's colour fills a wide box in the top half with text in it.
pub fn assert_shows_table(w: u32, h: u32, pixels: &[[u8; 3]]) {
    assert_eq!((w, h), WINDOW, "screenshot size");

    // Not blank: the luminance varies and there is dark text.
    let lum: Vec<f64> = pixels
        .iter()
        .map(|p| 0.299 * f64::from(p[0]) + 0.587 * f64::from(p[1]) + 0.114 * f64::from(p[2]))
        .collect();
    let mean = lum.iter().sum::<f64>() / lum.len() as f64;
    let var = lum.iter().map(|l| (l - mean) * (l - mean)).sum::<f64>() / lum.len() as f64;
    assert!(
        var > 100.0,
        "screenshot looks blank (luminance variance {var:.1})"
    );
    let dark = lum.iter().filter(|&&l| l < 90.0).count();
    assert!(dark > 5_000, "only {dark} dark (text) pixels");

    // The table is shown: its header colour fills a wide box in the top half of the page, with
    // text inside, and the miss (red) and pass (green) cells are painted.
    // Rows of the header are long runs of its colour (figures below may hold a stray pixel of
    // it, so only rows with many count).
    let (mut x0, mut y0, mut x1, mut y1, mut count) = (u32::MAX, u32::MAX, 0, 0, 0usize);
    for y in 0..h {
        let row = &pixels[(y * w) as usize..((y + 1) * w) as usize];
        let xs: Vec<u32> = (0..w)
            .filter(|&x| near(row[x as usize], HEADER_BLUE))
            .collect();
        if xs.len() >= 200 {
            (x0, x1) = (x0.min(xs[0]), x1.max(xs[xs.len() - 1]));
            (y0, y1) = (y0.min(y), y1.max(y));
            count += xs.len();
        }
    }
    assert!(
        count > 5_000,
        "only {count} pixels of the table header colour: the table is not shown"
    );
    assert!(x1 - x0 > 600, "the table header is {} px wide", x1 - x0);
    assert!(y1 - y0 > 30, "the table header is {} px high", y1 - y0);
    assert!(
        y1 < h / 2,
        "the table header is not in the top half (ends at y = {y1})"
    );
    let header_dark = (y0..=y1)
        .flat_map(|y| (x0..=x1).map(move |x| (x, y)))
        .filter(|&(x, y)| lum[(y * w + x) as usize] < 90.0)
        .count();
    assert!(
        header_dark > 300,
        "no text in the table header ({header_dark} dark pixels)"
    );
}
