//! `dalembert animate` end to end: the page renders in headless Chromium without console errors,
//! and the pixels at the simulated body positions carry the bodies' colours at two times.
//!
//! The browser is Debian's `chromium` (`.ci/run` installs it); set `DALEMBERT_CHROMIUM` to use
//! another. Without a browser the rendering test is skipped with a message, except under CI
//! (`CI` set), where a missing browser fails it.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{dalembert, scene, tmp};

fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("DALEMBERT_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|d| ["chromium", "chromium-browser", "google-chrome"].map(|n| d.join(n)))
        .find(|p| p.is_file())
}

/// Runs headless Chromium on `page` at window size `size` with `extra` arguments; returns stdout.
/// The browser, or `None` with a SKIPPED line outside CI (in CI a missing browser fails).
fn chromium_or_skip() -> Option<PathBuf> {
    let browser = chromium();
    if browser.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must have Chromium (.ci/run installs Debian's package)"
        );
        eprintln!("SKIPPED: no Chromium found (apt-get install chromium, or set DALEMBERT_CHROMIUM)");
    }
    browser
}

fn browse(browser: &Path, page: &str, size: (usize, usize), extra: &[&str]) -> String {
    // A profile of its own per browser: tests run at once, and Chromium locks its profile.
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let profile = tmp(&format!("profile-{run}"));
    let out = Command::new(browser)
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
            "--force-device-scale-factor=1",
        ])
        .arg(format!("--window-size={},{}", size.0, size.1))
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(page)
        .output()
        .expect("chromium runs");
    assert!(
        out.status.success(),
        "chromium failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into()
}

/// The window size that gives a page dumped with `--dump-dom` the viewport a screenshot at `size`
/// has (a dumping window shows less of its height): probes `page` once with `extra` arguments.
fn dump_window(browser: &Path, page: &str, size: (usize, usize), extra: &[&str]) -> (usize, usize) {
    let args: Vec<&str> = ["--dump-dom"].into_iter().chain(extra.iter().copied()).collect();
    let probe = browse(browser, page, size, &args);
    let seen = attribute(&probe, "<body", "data-viewport").unwrap();
    let seen_height: usize = seen.split('x').nth(1).unwrap().parse().unwrap();
    (size.0, 2 * size.1 - seen_height)
}

/// The value of attribute `name` on the element whose tag starts with `tag` in a dumped DOM.
fn attribute(dom: &str, tag: &str, name: &str) -> Option<String> {
    let start = dom.find(tag)?;
    let end = start + dom[start..].find('>')?;
    let element = &dom[start..end];
    let key = format!("{name}=\"");
    let at = element.find(&key)? + key.len();
    let len = element[at..].find('"')?;
    Some(element[at..at + len].replace("&quot;", "\"").replace("&amp;", "&"))
}

/// Number after `"key":` in a flat JSON object.
fn json_number(json: &str, key: &str) -> f64 {
    let k = format!("\"{key}\":");
    let at = json.find(&k).unwrap() + k.len();
    let end = json[at..].find([',', '}']).unwrap();
    json[at..at + end].parse().unwrap()
}

struct Png {
    width: usize,
    rgba: Vec<u8>,
}

impl Png {
    fn read(path: &Path) -> Png {
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        let channels = info.color_type.samples();
        let rgba = buf[..info.buffer_size()]
            .chunks(channels)
            .flat_map(|p| [p[0], p[1], p[2], if channels == 4 { p[3] } else { 255 }])
            .collect();
        Png {
            width: info.width as usize,
            rgba,
        }
    }

    fn pixel(&self, x: usize, y: usize) -> [u8; 3] {
        let k = 4 * (y * self.width + x);
        [self.rgba[k], self.rgba[k + 1], self.rgba[k + 2]]
    }

    /// True when a pixel within `r` of `(x, y)` is within 40 (per channel) of `color`.
    fn has_color_near(&self, x: f64, y: f64, r: i64, color: [u8; 3]) -> bool {
        let (cx, cy) = (x.round() as i64, y.round() as i64);
        (-r..=r).any(|dy| {
            (-r..=r).any(|dx| {
                let p = self.pixel((cx + dx) as usize, (cy + dy) as usize);
                (0..3).all(|i| (i32::from(p[i]) - i32::from(color[i])).abs() <= 40)
            })
        })
    }
}

fn hex(c: &str) -> [u8; 3] {
    let v = u32::from_str_radix(c.trim_start_matches('#'), 16).unwrap();
    [(v >> 16) as u8, (v >> 8) as u8, v as u8]
}

/// Reads `t` and each body's `x, y` from a result CSV.
fn positions(csv: &Path, bodies: &[&str]) -> Vec<(f64, Vec<[f64; 2]>)> {
    let mut rdr = csv::Reader::from_path(csv).unwrap();
    let header = rdr.headers().unwrap().clone();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let cols: Vec<[usize; 2]> = bodies
        .iter()
        .map(|b| [col(&format!("{b}.x")), col(&format!("{b}.y"))])
        .collect();
    rdr.records()
        .map(|r| {
            let r = r.unwrap();
            let v = |k: usize| r[k].parse::<f64>().unwrap();
            (v(0), cols.iter().map(|c| [v(c[0]), v(c[1])]).collect())
        })
        .collect()
}

#[test]
fn replay_of_a_saved_run_is_the_same_page_as_the_simulation() {
    let csv = tmp("fb.csv");
    let (ok, _, err) = dalembert(&[
        "simulate",
        &scene("four-bar.toml"),
        "--end",
        "2",
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let direct = tmp("direct.html");
    let replay = tmp("replay.html");
    for (page, from) in [(&direct, None), (&replay, Some(&csv))] {
        let mut args = vec![
            "animate".to_string(),
            scene("four-bar.toml"),
            "--end".into(),
            "2".into(),
            "--output".into(),
            page.display().to_string(),
        ];
        if let Some(c) = from {
            args.extend(["--from".into(), c.display().to_string()]);
        }
        let args: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
        let (ok, out, err) = dalembert(&args);
        assert!(ok && out.contains("201 frames"), "{out}{err}");
    }
    // The CSV holds shortest round-trip decimals, so replaying it gives the very same numbers.
    assert_eq!(std::fs::read(&direct).unwrap(), std::fs::read(&replay).unwrap());
    let html = std::fs::read_to_string(&direct).unwrap();
    assert!(
        !html.contains("src=\"http") && !html.contains("<link"),
        "self-contained"
    );
}

#[test]
fn bad_traces_and_mismatched_csv_get_one_line_errors() {
    let out = tmp("bad.html");
    let o = out.to_str().unwrap();
    let fb = scene("four-bar.toml");
    for (trace, expected) in [
        (
            "nobody:0.5,0",
            "--trace 'nobody:0.5,0': unknown body 'nobody' (bodies: crank, coupler, rocker)",
        ),
        ("coupler:0.5", "--trace 'coupler:0.5': '0.5' is not two numbers X,Y"),
        (
            "coupler:a,0",
            "--trace 'coupler:a,0': 'a,0' is not two finite numbers X,Y",
        ),
        ("coupler", "--trace 'coupler': expected BODY:X,Y"),
    ] {
        let (ok, _, err) = dalembert(&["animate", &fb, "--end", "0.1", "--trace", trace, "--output", o]);
        assert!(
            !ok && err.lines().count() == 1 && err.contains(expected),
            "{trace}: {err}"
        );
    }
    // A run of another scene does not match: the missing column is named.
    let csv = tmp("pendulum.csv");
    let (ok, _, err) = dalembert(&[
        "simulate",
        &scene("pendulum.toml"),
        "--end",
        "0.1",
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let c = csv.to_str().unwrap();
    let (ok, _, err) = dalembert(&["animate", &fb, "--from", c, "--output", o]);
    assert!(!ok && err.lines().count() == 1, "{err}");
    assert!(
        err.contains(&format!("{c}:1: does not match the scene: no column 'crank.x'")),
        "{err}"
    );
    // A corrupted row is named by its line.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[3] = lines[3].replacen(',', ",junk,", 1);
    std::fs::write(&csv, lines.join("\n")).unwrap();
    let (ok, _, err) = dalembert(&["animate", &scene("pendulum.toml"), "--from", c, "--output", o]);
    assert!(
        !ok && err.lines().count() == 1 && err.contains(&format!("{c}:4: malformed CSV")),
        "{err}"
    );
}

#[test]
fn the_page_renders_the_simulated_positions_in_chromium() {
    let Some(browser) = chromium_or_skip() else {
        return;
    };
    let csv = tmp("render.csv");
    let page = tmp("render.html");
    let (ok, _, err) = dalembert(&[
        "simulate",
        &scene("four-bar.toml"),
        "--end",
        "2",
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let (ok, _, err) = dalembert(&[
        "animate",
        &scene("four-bar.toml"),
        "--from",
        csv.to_str().unwrap(),
        "--trace",
        "coupler:0.5,0",
        "--output",
        page.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let bodies = ["crank", "coupler", "rocker"];
    let rows = positions(&csv, &bodies);
    let at = |t: f64| rows.iter().find(|r| (r.0 - t).abs() < 1e-9).unwrap().1.clone();
    // A screenshot's viewport is the window size; `--dump-dom` keeps room for browser chrome, so
    // its window is enlarged by the difference (checked below through the page's own report).
    let size = (900, 600);
    let dump_size = dump_window(&browser, &format!("file://{}#t=0", page.display()), size, &[]);
    let mut shots = Vec::new();
    for t in [0.5, 1.5] {
        let url = format!("file://{}#t={t}", page.display());
        let dom = browse(&browser, &url, dump_size, &["--dump-dom"]);
        assert_eq!(
            attribute(&dom, "<body", "data-viewport"),
            Some(format!("{}x{}", size.0, size.1)),
            "the layout measured is the one photographed"
        );
        assert_eq!(
            attribute(&dom, "<body", "data-status").as_deref(),
            Some("ready"),
            "{dom}"
        );
        assert_eq!(attribute(&dom, "<body", "data-errors"), None, "console errors");
        assert_eq!(
            attribute(&dom, "<body", "data-time").as_deref(),
            Some(t.to_string().as_str())
        );
        let view = attribute(&dom, "<canvas", "data-view").unwrap();
        let (scale, ox, oy) = (
            json_number(&view, "scale"),
            json_number(&view, "ox"),
            json_number(&view, "oy"),
        );
        let colors: Vec<[u8; 3]> = view.split('#').skip(1).map(|c| hex(&c[..6])).collect();
        let shot = tmp(&format!("shot-{t}.png"));
        browse(&browser, &url, size, &[&format!("--screenshot={}", shot.display())]);
        let png = Png::read(&shot);
        assert_eq!((png.width, png.rgba.len() / 4 / png.width), size);
        let to_px = move |p: [f64; 2]| (ox + scale * p[0], oy - scale * p[1]);
        // Each body's centre of mass (the middle of its rod) is drawn in the body's colour.
        for (k, p) in at(t).into_iter().enumerate() {
            let (x, y) = to_px(p);
            assert!(
                png.has_color_near(x, y, 1, colors[k]),
                "t = {t}: {} at ({x:.1}, {y:.1}) px is not drawn in {:?}",
                bodies[k],
                colors[k]
            );
        }
        shots.push((png, to_px));
    }
    // The pictures differ where the mechanism moved: the coupler's centre at t = 1.5 s lies where
    // nothing of the coupler was drawn at t = 0.5 s.
    let (x0, y0) = (shots[0].1)(at(0.5)[1]);
    let (x1, y1) = (shots[1].1)(at(1.5)[1]);
    assert!((x1 - x0).hypot(y1 - y0) > 30.0, "the coupler moves visibly");
    let coupler = hex("#d62728");
    assert!(!shots[0].0.has_color_near(x1, y1, 1, coupler));
    assert!(shots[1].0.has_color_near(x1, y1, 1, coupler));
    let differing = shots[0]
        .0
        .rgba
        .chunks(4)
        .zip(shots[1].0.rgba.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    assert!(differing > 2000, "only {differing} pixels changed");
}

/// The pixel of global point `p` on the screenshot, by the page's own camera (`data-view`: the
/// column-major view-projection matrix and the canvas' rectangle in the window).
fn project(view: &str, p: [f64; 3]) -> (f64, f64) {
    let at = view.find("\"matrix\":[").unwrap() + 10;
    let end = at + view[at..].find(']').unwrap();
    let m: Vec<f64> = view[at..end].split(',').map(|x| x.parse().unwrap()).collect();
    let row = |r: usize| m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
    let w = row(3);
    let (x, y) = (row(0) / w, row(1) / w);
    let (left, top) = (json_number(view, "left"), json_number(view, "top"));
    let (width, height) = (json_number(view, "width"), json_number(view, "height"));
    (left + 0.5 * (x + 1.0) * width, top + 0.5 * (1.0 - y) * height)
}

/// Reads `t` and each body's centre of mass `x, y, z` from a result CSV.
fn centres(csv: &Path, bodies: &[String]) -> Vec<(f64, Vec<[f64; 3]>)> {
    let mut rdr = csv::Reader::from_path(csv).unwrap();
    let header = rdr.headers().unwrap().clone();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let cols: Vec<[usize; 3]> = bodies
        .iter()
        .map(|b| [col(&format!("{b}.x")), col(&format!("{b}.y")), col(&format!("{b}.z"))])
        .collect();
    rdr.records()
        .map(|r| {
            let r = r.unwrap();
            let v = |k: usize| r[k].parse::<f64>().unwrap();
            (v(0), cols.iter().map(|c| [v(c[0]), v(c[1]), v(c[2])]).collect())
        })
        .collect()
}

/// Every pixel within `r` of `(x, y)` on `png` that is within `tolerance` (per channel) of `color`.
fn count_near(png: &Png, (x, y): (f64, f64), r: i64, color: [u8; 3], tolerance: i32) -> usize {
    let (cx, cy) = (x.round() as i64, y.round() as i64);
    let height = (png.rgba.len() / 4 / png.width) as i64;
    let mut n = 0;
    for dy in -r..=r {
        for dx in -r..=r {
            let (px, py) = (cx + dx, cy + dy);
            if px < 0 || py < 0 || px >= png.width as i64 || py >= height {
                continue;
            }
            let p = png.pixel(px as usize, py as usize);
            n += usize::from((0..3).all(|i| (i32::from(p[i]) - i32::from(color[i])).abs() <= tolerance));
        }
    }
    n
}

/// Every spatial scene, both shipped robots and the MJCF arm in the 3D viewer: the page loads three.js from
/// itself and reports no script error; at each time the centre of mass of every body (from the
/// CSV of the same run, projected by the page's own camera) carries its marker, a 4 px square of
/// #111111 centred there: within 1 px of the point, at least 4 of its pixels (a drawing 5 px
/// off leaves none); between two times the picture changes where a body moved.
#[test]
fn the_3d_viewer_draws_every_spatial_scene_where_the_run_puts_it() {
    let Some(browser) = chromium_or_skip() else {
        return;
    };
    let budget = "--virtual-time-budget=5000"; // three.js is imported before the first drawing
    let size = (800, 560);
    let mut cases: Vec<(String, Vec<f64>)> = [
        "arm-6",
        "bricard",
        "heavy-top",
        "rssr",
        "slider-crank-3d",
        "spatial-chain-16",
    ]
    .iter()
    .map(|s| (scene(&format!("{s}.toml")), vec![0.6]))
    .collect();
    cases.push((scene("robots/ur5.urdf"), vec![0.6]));
    cases.push((scene("robots/kinova.urdf"), vec![0.6]));
    cases.push((scene("mjcf/arm-3.xml"), vec![0.6]));
    cases.push((scene("robots/ur5-swing.toml"), vec![0.2, 0.7]));
    cases[0].1 = vec![0.25, 0.75];
    let mut dump_size = None;
    for (path, times) in &cases {
        let name = Path::new(path).file_stem().unwrap().to_string_lossy().into_owned();
        let (csv, page) = (tmp(&format!("{name}-3d.csv")), tmp(&format!("{name}-3d.html")));
        let (ok, _, err) = dalembert(&[
            "simulate",
            path,
            "--end",
            "0.8",
            "--every",
            "0.05",
            "--output",
            csv.to_str().unwrap(),
        ]);
        assert!(ok, "{name}: {err}");
        let (ok, _, err) = dalembert(&[
            "animate",
            path,
            "--from",
            csv.to_str().unwrap(),
            "--output",
            page.to_str().unwrap(),
        ]);
        assert!(ok, "{name}: {err}");
        let bodies: Vec<String> = dalembert::Scene::from_path(path).unwrap().model.body_names();
        let rows = centres(&csv, &bodies);
        let at = |t: f64| rows.iter().find(|r| (r.0 - t).abs() < 1e-9).unwrap().1.clone();
        // The window that gives a dumped page the screenshot's viewport (see the planar test).
        let dump = *dump_size
            .get_or_insert_with(|| dump_window(&browser, &format!("file://{}#t=0", page.display()), size, &[budget]));
        let mut shots = Vec::new();
        for &t in times {
            let url = format!("file://{}#t={t}", page.display());
            let dom = browse(&browser, &url, dump, &["--dump-dom", budget]);
            assert_eq!(
                attribute(&dom, "<body", "data-status").as_deref(),
                Some("ready"),
                "{name}: {dom}"
            );
            assert_eq!(attribute(&dom, "<body", "data-errors"), None, "{name}: script errors");
            assert_eq!(
                attribute(&dom, "<body", "data-viewport"),
                Some(format!("{}x{}", size.0, size.1))
            );
            let view = attribute(&dom, "<canvas", "data-view").unwrap();
            let shot = tmp(&format!("{name}-{t}.png"));
            browse(
                &browser,
                &url,
                size,
                &[&format!("--screenshot={}", shot.display()), budget],
            );
            let png = Png::read(&shot);
            for (k, c) in at(t).into_iter().enumerate() {
                let px = project(&view, c);
                let n = count_near(&png, px, 1, [0x11; 3], 12);
                assert!(
                    n >= 4,
                    "{name} t = {t}: {}'s centre at ({:.1}, {:.1}) px has no marker ({n} pixels)",
                    bodies[k],
                    px.0,
                    px.1
                );
            }
            shots.push((png, view));
        }
        if let [(a, view_a), (b, view_b)] = shots.as_slice() {
            // The body that moved most on the screen: its marker is where it is at each time only.
            let (t_a, t_b) = (times[0], times[1]);
            let moved = (0..bodies.len())
                .map(|k| (k, project(view_a, at(t_a)[k]), project(view_b, at(t_b)[k])))
                .max_by(|x, y| {
                    let d = |p: &(usize, (f64, f64), (f64, f64))| (p.2 .0 - p.1 .0).hypot(p.2 .1 - p.1 .1);
                    d(x).total_cmp(&d(y))
                })
                .unwrap();
            let (_, pa, pb) = moved;
            assert!((pb.0 - pa.0).hypot(pb.1 - pa.1) > 20.0, "{name}: nothing moves visibly");
            assert_eq!(
                count_near(a, pb, 1, [0x11; 3], 12),
                0,
                "{name}: the later marker is already drawn"
            );
            assert!(count_near(b, pb, 1, [0x11; 3], 12) >= 4);
            let differing = a.rgba.chunks(4).zip(b.rgba.chunks(4)).filter(|(x, y)| x != y).count();
            assert!(differing > 2000, "{name}: only {differing} pixels changed");
        }
    }
}

#[test]
fn every_shipped_scene_animates() {
    let dir = format!("{}/../../scenes", env!("CARGO_MANIFEST_DIR"));
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let page = tmp(&format!("{}.html", path.file_stem().unwrap().to_string_lossy()));
        let (ok, out, err) = dalembert(&[
            "animate",
            path.to_str().unwrap(),
            "--end",
            "0.5",
            "--every",
            "0.01",
            "--output",
            page.to_str().unwrap(),
        ]);
        let scene = dalembert::Scene::from_path(&path).unwrap();
        assert!(ok, "{}: {err}", path.display());
        assert!(out.contains("51 frames"), "{}: {out}", path.display());
        let html = std::fs::read_to_string(&page).unwrap();
        for b in scene.drawing.body_names() {
            assert!(html.contains(&format!("\"name\":\"{b}\"")), "{b}");
        }
        // A spatial scene gets the 3D viewer, with three.js inlined; a planar one the 2D viewer.
        assert_eq!(
            html.contains("three-source"),
            scene.model.is_spatial(),
            "{}",
            path.display()
        );
        count += 1;
    }
    assert!(count >= 14, "found {count} scenes");
}

/// The pose rows of one body (`t`, centre, Euler parameters) from a result CSV.
fn poses(csv: &Path, body: &str) -> Vec<(f64, [f64; 3], [f64; 4])> {
    let mut rdr = csv::Reader::from_path(csv).unwrap();
    let header = rdr.headers().unwrap().clone();
    let col = |n: &str| header.iter().position(|h| h == format!("{body}.{n}")).unwrap();
    let c = ["x", "y", "z", "e0", "e1", "e2", "e3"].map(col);
    rdr.records()
        .map(|r| {
            let r = r.unwrap();
            let v = |k: usize| r[c[k]].parse::<f64>().unwrap();
            (r[0].parse().unwrap(), [v(0), v(1), v(2)], [v(3), v(4), v(5), v(6)])
        })
        .collect()
}

/// `R(e) a`: the rotation of Euler parameters `e` applied to `a`.
fn rotate(e: [f64; 4], a: [f64; 3]) -> [f64; 3] {
    let [e0, e1, e2, e3] = e;
    let r = [
        [
            e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3,
            2.0 * (e1 * e2 - e0 * e3),
            2.0 * (e1 * e3 + e0 * e2),
        ],
        [
            2.0 * (e1 * e2 + e0 * e3),
            e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3,
            2.0 * (e2 * e3 - e0 * e1),
        ],
        [
            2.0 * (e1 * e3 - e0 * e2),
            2.0 * (e2 * e3 + e0 * e1),
            e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3,
        ],
    ];
    r.map(|row| row[0] * a[0] + row[1] * a[1] + row[2] * a[2])
}

/// Pixels within `r` of `(x, y)` in the first body's blue (#1f77b4) as lighting shades it: blue
/// well above red, and not the white background or the grey grid.
fn blue_near(png: &Png, (x, y): (f64, f64), r: i64) -> usize {
    let (cx, cy) = (x.round() as i64, y.round() as i64);
    let mut n = 0;
    for dy in -r..=r {
        for dx in -r..=r {
            let p = png.pixel((cx + dx) as usize, (cy + dy) as usize);
            n += usize::from(i32::from(p[2]) > i32::from(p[0]) + 50);
        }
    }
    n
}

/// Meshes in the 3D viewer: `tests/data/meshes/three-cubes.toml` draws a spherical pendulum with
/// three cubes of side 0.2 m, one per format (OBJ in metres, COLLADA in centimetres with y up and
/// a node transform, binary STL in millimetres scaled by its visual), each 0.6 m from the centre of
/// mass along one body axis. At two times, each cube's centre (from the CSV's pose of the body,
/// projected by the page's own camera; a cube is about 30 px wide here) is covered by the body's
/// colour (at least 40 of the 49 pixels within 3 px), and the point opposite it (0.6 m the other
/// way) is not (at most 3): a mesh in the wrong units, axes or place fails one or the other.
///
/// The same pendulum in MJCF (`three-cubes.xml`: `<asset>` meshes, the OBJ along x and y, the STL
/// along z, and a group-3 sphere at the centre of mass that is not drawn, as in MuJoCo's viewer)
/// passes the same check.
#[test]
fn the_3d_viewer_draws_each_mesh_where_its_body_puts_it() {
    let Some(browser) = chromium_or_skip() else {
        return;
    };
    for (file, formats) in [
        ("three-cubes.toml", ["OBJ", "COLLADA", "STL"]),
        ("three-cubes.xml", ["OBJ", "OBJ", "STL"]),
    ] {
        cubes_where_their_body_puts_them(&browser, file, formats);
    }
}

/// [`the_3d_viewer_draws_each_mesh_where_its_body_puts_it`] on `tests/data/meshes/<file>`, whose
/// cubes along the body's x, y and z come from meshes in `formats`.
fn cubes_where_their_body_puts_them(browser: &Path, file: &str, formats: [&str; 3]) {
    let path = format!("{}/../../tests/data/meshes/{file}", env!("CARGO_MANIFEST_DIR"));
    let (csv, page) = (tmp(&format!("{file}.csv")), tmp(&format!("{file}.html")));
    let csv_arg = csv.to_str().unwrap();
    let (ok, _, err) = dalembert(&["simulate", &path, "--every", "0.05", "--output", csv_arg]);
    assert!(ok, "{err}");
    let (ok, _, err) = dalembert(&["animate", &path, "--from", csv_arg, "--output", page.to_str().unwrap()]);
    assert!(ok, "{err}");
    let rows = poses(&csv, "bob");
    let budget = "--virtual-time-budget=5000";
    let size = (800, 560);
    let probe = browse(
        browser,
        &format!("file://{}#t=0", page.display()),
        size,
        &["--dump-dom", budget],
    );
    let seen: usize = attribute(&probe, "<body", "data-viewport")
        .unwrap()
        .split('x')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    let dump = (size.0, 2 * size.1 - seen);
    for t in [0.25, 0.75] {
        let url = format!("file://{}#t={t}", page.display());
        let dom = browse(browser, &url, dump, &["--dump-dom", budget]);
        assert_eq!(attribute(&dom, "<body", "data-status").as_deref(), Some("ready"));
        assert_eq!(attribute(&dom, "<body", "data-errors"), None, "script errors");
        assert_eq!(attribute(&dom, "<body", "data-meshes").as_deref(), Some("3"), "{file}");
        let view = attribute(&dom, "<canvas", "data-view").unwrap();
        let shot = tmp(&format!("{file}-{t}.png"));
        browse(
            browser,
            &url,
            size,
            &[&format!("--screenshot={}", shot.display()), budget],
        );
        let png = Png::read(&shot);
        let (_, c, e) = rows.iter().find(|r| (r.0 - t).abs() < 1e-9).copied().unwrap();
        for (k, format) in formats.iter().enumerate() {
            let mut along = [0.0; 3];
            along[k] = 0.6;
            let d = rotate(e, along);
            let at = |s: f64| project(&view, [c[0] + s * d[0], c[1] + s * d[1], c[2] + s * d[2]]);
            let (here, opposite) = (blue_near(&png, at(1.0), 3), blue_near(&png, at(-1.0), 3));
            assert!(
                here >= 40,
                "{file} t = {t}: the {format} cube is not at {:?} ({here} of 49 pixels)",
                at(1.0)
            );
            assert!(
                opposite <= 3,
                "{file} t = {t}: the {format} cube's opposite point is drawn ({opposite} of 49)"
            );
        }
    }
}

/// Reaction arrows (`#reactions` in the address, a check box on the page): a pendulum on a
/// spherical joint, swinging. At each time the arrow at the pivot points along the force the bob
/// exerts on the ground (the CSV's `pivot.fx, fy, fz`, at the page's own scale,
/// `data-reaction-scale`): its head, drawn in #c0392b, lies 90 % of the way to the tip (at least
/// 3 pixels of that colour within 3 px) and nothing of it lies on the opposite side. The page made
/// from the run and the one replayed from the CSV carry the same arrows.
#[test]
fn the_3d_viewer_draws_each_joint_reaction_along_its_force() {
    let Some(browser) = chromium_or_skip() else {
        return;
    };
    let budget = "--virtual-time-budget=5000";
    let size = (800, 560);
    let path = tmp("swinging-bob.toml");
    std::fs::write(
        &path,
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n[[bodies]]\nname = \"bob\"\nmass = 3.0\nshape = { sphere = 0.1 }\nposition = [0.5, 0.2, -0.6]\n[[joints]]\nname = \"pivot\"\ntype = \"spherical\"\nbodies = [\"ground\", \"bob\"]\nat = [0.0, 0.0, 0.0]\n[simulation]\nend = 1.0\noutput_every = 0.01\n",
    )
    .unwrap();
    let path = path.to_str().unwrap();
    let (csv, from_run, replayed) = (tmp("bob.csv"), tmp("bob-run.html"), tmp("bob-csv.html"));
    let (ok, _, err) = dalembert(&["simulate", path, "--output", csv.to_str().unwrap()]);
    assert!(ok, "{err}");
    let (ok, _, err) = dalembert(&["animate", path, "--output", from_run.to_str().unwrap()]);
    assert!(ok, "{err}");
    let (ok, _, err) = dalembert(&[
        "animate",
        path,
        "--from",
        csv.to_str().unwrap(),
        "--output",
        replayed.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let data = |p: &Path| {
        let page = std::fs::read_to_string(p).unwrap();
        let at = page.find("\"reactions\":\"").unwrap() + 13;
        page[at..at + page[at..].find('"').unwrap()].to_string()
    };
    assert_eq!(data(&from_run), data(&replayed), "the run's page and the replay's");
    assert!(data(&from_run).len() > 100);
    let mut rdr = csv::Reader::from_path(&csv).unwrap();
    let header = rdr.headers().unwrap().clone();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let (ft, fx, fy, fz) = (col("t"), col("pivot.fx"), col("pivot.fy"), col("pivot.fz"));
    let rows: Vec<Vec<f64>> = rdr
        .records()
        .map(|r| r.unwrap().iter().map(|v| v.parse().unwrap()).collect())
        .collect();
    let dump = dump_window(
        &browser,
        &format!("file://{}#t=0&reactions", from_run.display()),
        size,
        &[budget],
    );
    for t in [0.3, 0.6] {
        let url = format!("file://{}#t={t}&reactions", from_run.display());
        let dom = browse(&browser, &url, dump, &["--dump-dom", budget]);
        assert_eq!(attribute(&dom, "<body", "data-errors"), None, "script errors");
        assert_eq!(attribute(&dom, "<body", "data-reactions").as_deref(), Some("1"));
        let scale: f64 = attribute(&dom, "<body", "data-reaction-scale")
            .unwrap()
            .parse()
            .unwrap();
        let view = attribute(&dom, "<canvas", "data-view").unwrap();
        let shot = tmp(&format!("bob-{t}.png"));
        browse(
            &browser,
            &url,
            size,
            &[&format!("--screenshot={}", shot.display()), budget],
        );
        let png = Png::read(&shot);
        let row = rows.iter().find(|r| (r[ft] - t).abs() < 1e-9).unwrap();
        let f = [row[fx], row[fy], row[fz]];
        let (head, behind) = arrow_pixels(&png, &view, ([0.0; 3], f, scale), [0xc0, 0x39, 0x2b]);
        assert!(
            head >= 3,
            "t = {t}: no arrow head at 90 % of the force {f:?} ({head} pixels)"
        );
        assert_eq!(behind, 0, "t = {t}: the arrow points the other way");
    }
}

/// The pixels of `colour` within 3 px of where the 3D viewer's arrow of force `f` from `from`
/// (`scale` newtons per metre, the page's `data-reaction-scale`) has its head, 90 % of the way
/// to its tip, and of the point as far on the opposite side: `(head, behind)`.
fn arrow_pixels(png: &Png, view: &str, (from, f, scale): ([f64; 3], [f64; 3], f64), colour: [u8; 3]) -> (usize, usize) {
    let along = |k: f64| [0, 1, 2].map(|i| from[i] + k * f[i] / scale);
    let count = |k: f64| count_near(png, project(view, along(k)), 3, colour, 10);
    (count(0.9), count(-0.9))
}

/// Contact force arrows (shown unless `#nocontacts`): a ball set down on a floor at its resting
/// penetration, sliding at 2 m/s with `μ = 0.3`, and a ball resting on a rigid frictionless
/// incline of 30° (pressed along its normal). While it slides the arrow at its contact point
/// (the CSV's `floor.px, py, pz`) points along the contact's force on it (`floor.fx, fy, fz`:
/// `m g` up and `μ m g` against the sliding, at the page's own scale, `data-reaction-scale`): its
/// head, drawn in #16a085, lies 90 % of the way to the tip (at least 3 pixels of that colour
/// within 3 px) and nothing of it on the opposite side; `#nocontacts` hides it.
#[test]
fn the_3d_viewer_draws_each_contact_force_at_its_point() {
    let Some(browser) = chromium_or_skip() else {
        return;
    };
    let depth = (9.81f64 / 1e6).powf(1.0 / 1.5);
    let compliant = format!("[scene]\ngravity = [0.0, 0.0, -9.81]\n[[bodies]]\nname = \"ball\"\nmass = 1.0\nshape = {{ sphere = 0.1 }}\nposition = [0.0, 0.0, {}]\nvelocity = [2.0, 0.0, 0.0]\n[[forces]]\nname = \"floor\"\ntype = \"sphere-plane\"\nbody = \"ball\"\nradius = 0.1\nplane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\nstiffness = 1e6\nfriction = 0.3\n[simulation]\nend = 0.2\nintegrator = \"rk4\"\nstep = 1e-4\noutput_every = 0.01\n", 0.1 - depth);
    // A rigid frictionless contact: a ball at rest on a 30° incline, pressed along its normal.
    let (s, c) = (0.5f64, 0.75f64.sqrt());
    let rigid = format!("[scene]\ngravity = [0.0, 0.0, -9.81]\n[[bodies]]\nname = \"ball\"\nmass = 1.0\nshape = {{ sphere = 0.1 }}\nposition = [0.0, {:?}, {:?}]\n[[forces]]\nname = \"floor\"\ntype = \"sphere-plane\"\nbody = \"ball\"\nradius = 0.1\nplane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, {:?}, {c:?}] }}\nrigid = true\n[simulation]\nend = 0.2\nintegrator = \"rk4\"\nstep = 1e-4\noutput_every = 0.01\n", -0.1 * s, 0.1 * c, -s);
    contact_arrows(&browser, "sliding-ball", &compliant, true);
    contact_arrows(&browser, "ball-on-incline", &rigid, false);
}

/// The scene `text` written as `<name>.toml`, simulated into `<name>.csv` and animated into
/// `<name>.html`: the CSV's header and rows, and the page.
fn simulated_page(name: &str, text: &str) -> (csv::StringRecord, Vec<Vec<f64>>, PathBuf) {
    let path = tmp(&format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    let path = path.to_str().unwrap();
    let (csv, page) = (tmp(&format!("{name}.csv")), tmp(&format!("{name}.html")));
    let (ok, _, err) = dalembert(&["simulate", path, "--output", csv.to_str().unwrap()]);
    assert!(ok, "{err}");
    let (ok, _, err) = dalembert(&["animate", path, "--output", page.to_str().unwrap()]);
    assert!(ok, "{err}");
    let mut rdr = csv::Reader::from_path(&csv).unwrap();
    let header = rdr.headers().unwrap().clone();
    let rows = rdr
        .records()
        .map(|r| r.unwrap().iter().map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows, page)
}

/// [`the_3d_viewer_draws_each_contact_force_at_its_point`] on the scene `text` (a ball and its
/// contact `floor`), whose force has friction against the sliding along x where `sliding`.
fn contact_arrows(browser: &Path, name: &str, text: &str, sliding: bool) {
    let budget = "--virtual-time-budget=5000";
    let size = (800, 560);
    let (header, rows, page) = simulated_page(name, text);
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let dump = dump_window(browser, &format!("file://{}#t=0", page.display()), size, &[budget]);
    let green = [0x16, 0xa0, 0x85];
    for t in [0.05, 0.08] {
        let url = format!("file://{}#t={t}", page.display());
        let dom = browse(browser, &url, dump, &["--dump-dom", budget]);
        assert_eq!(attribute(&dom, "<body", "data-errors"), None, "script errors");
        assert_eq!(attribute(&dom, "<body", "data-contacts").as_deref(), Some("1"));
        let scale: f64 = attribute(&dom, "<body", "data-reaction-scale")
            .unwrap()
            .parse()
            .unwrap();
        let view = attribute(&dom, "<canvas", "data-view").unwrap();
        let row = rows.iter().find(|r| (r[col("t")] - t).abs() < 1e-9).unwrap();
        let f = ["fx", "fy", "fz"].map(|k| row[col(&format!("floor.{k}"))]);
        let p = ["px", "py", "pz"].map(|k| row[col(&format!("floor.{k}"))]);
        if sliding {
            assert!(f[0] < -0.25 * f[2], "{name} t = {t}: sliding, the friction is {f:?}");
        }
        for (hash, shown) in [("", true), ("&nocontacts", false)] {
            let shot = tmp(&format!("{name}-{t}{hash}.png"));
            browse(
                browser,
                &format!("{url}{hash}"),
                size,
                &[&format!("--screenshot={}", shot.display()), budget],
            );
            let png = Png::read(&shot);
            let (head, behind) = arrow_pixels(&png, &view, (p, f, scale), green);
            match shown {
                true => assert!(
                    head >= 3,
                    "{name} t = {t}: no arrow head at 90 % of the force {f:?} ({head} pixels)"
                ),
                false => assert_eq!(head, 0, "{name} t = {t}: #nocontacts still draws the arrow"),
            }
            assert_eq!(behind, 0, "{name} t = {t}: the arrow points the other way");
        }
    }
}

/// A planar compliant contact's force (the CSV's `ground.fx, fy` at `ground.px, py`): a disk set
/// down on a line at its resting penetration, sliding at 2 m/s with `μ = 0.3`. At two times the
/// page draws an arrow (#e6007e) from the contact point along the force (`m g` up, `μ m g`
/// against the sliding): 2 cm along it, and nothing 2 cm the other way.
#[test]
fn the_planar_viewer_draws_a_compliant_contact_force_at_its_point() {
    let Some(browser) = chromium_or_skip() else {
        return;
    };
    let depth = (9.81f64 / 1e6).powf(1.0 / 1.5);
    let text = format!("[scene]\ngravity = [0.0, -9.81]\n[[bodies]]\nname = \"disk\"\nmass = 1.0\nshape = {{ disk = 0.1 }}\nposition = [0.0, {}]\nvelocity = [2.0, 0.0]\n[[forces]]\nname = \"ground\"\ntype = \"circle-line\"\nbody = \"disk\"\nradius = 0.1\nline = {{ point = [0.0, 0.0], normal = [0.0, 1.0] }}\nstiffness = 1e6\nfriction = 0.3\n[simulation]\nend = 0.2\nintegrator = \"rk4\"\nstep = 1e-4\noutput_every = 0.01\n", 0.1 - depth);
    let (header, rows, page) = simulated_page("sliding-disk", &text);
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let size = (900, 600);
    let magenta = hex("#e6007e");
    for t in [0.05, 0.1] {
        let url = format!("file://{}#t={t}", page.display());
        let dump_size = dump_window(&browser, &url, size, &[]);
        let dom = browse(&browser, &url, dump_size, &["--dump-dom"]);
        assert_eq!(attribute(&dom, "<body", "data-errors"), None, "console errors");
        assert_eq!(
            attribute(&dom, "<body", "data-compliant-contacts").as_deref(),
            Some("1")
        );
        let view = attribute(&dom, "<canvas", "data-view").unwrap();
        let (scale, ox, oy) = (
            json_number(&view, "scale"),
            json_number(&view, "ox"),
            json_number(&view, "oy"),
        );
        let to_px = |p: [f64; 2]| (ox + scale * p[0], oy - scale * p[1]);
        let row = rows.iter().find(|r| (r[col("t")] - t).abs() < 1e-9).unwrap();
        let f = [row[col("ground.fx")], row[col("ground.fy")]];
        let p = [row[col("ground.px")], row[col("ground.py")]];
        assert!(f[0] < -0.25 * f[1], "t = {t}: sliding, the friction is {f:?}");
        let unit = f.map(|c| c / f[0].hypot(f[1]));
        let shot = tmp(&format!("sliding-disk-{t}.png"));
        browse(&browser, &url, size, &[&format!("--screenshot={}", shot.display())]);
        let png = Png::read(&shot);
        let (x, y) = to_px([p[0] + 0.02 * unit[0], p[1] + 0.02 * unit[1]]);
        assert!(
            png.has_color_near(x, y, 3, magenta),
            "t = {t}: no arrow 2 cm along the force {f:?} at ({x:.0}, {y:.0}) px"
        );
        let (x, y) = to_px([p[0] - 0.02 * unit[0], p[1] - 0.02 * unit[1]]);
        assert!(
            !png.has_color_near(x, y, 3, magenta),
            "t = {t}: an arrow the other way at ({x:.0}, {y:.0}) px"
        );
    }
}

#[test]
fn the_planar_viewer_draws_a_cam_profile_and_the_contact_force_along_its_normal() {
    // scenes/cam-roller.toml at t = 0.125 s (the cam a quarter turn round): the page draws the
    // profile on the cam (its outline, in the cam's colour, at a profile point a half turn from
    // the roller, placed by the law the profile was made from), and an arrow of the contact force
    // from the contact point along the normal into the roller (the profile's normal there: the
    // pitch curve's, turned with the cam). Its force is the run's (`roller.normal` of that row,
    // the page's `data-contact-forces`).
    let Some(browser) = chromium_or_skip() else {
        return;
    };
    let csv = tmp("cam-roller.csv");
    let page = tmp("cam-roller.html");
    let (ok, _, err) = dalembert(&[
        "simulate",
        &scene("cam-roller.toml"),
        "--end",
        "0.25",
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let (ok, _, err) = dalembert(&[
        "animate",
        &scene("cam-roller.toml"),
        "--from",
        csv.to_str().unwrap(),
        "--output",
        page.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let t = 0.125;
    let size = (900, 600);
    let url = format!("file://{}#t={t}", page.display());
    let dump_size = dump_window(&browser, &url, size, &[]);
    let dom = browse(&browser, &url, dump_size, &["--dump-dom"]);
    assert_eq!(attribute(&dom, "<body", "data-errors"), None, "console errors");
    let mut rdr = csv::Reader::from_path(&csv).unwrap();
    let header = rdr.headers().unwrap().clone();
    let col = header.iter().position(|h| h == "roller.normal").unwrap();
    let force: f64 = rdr
        .records()
        .map(|r| r.unwrap())
        .find(|r| (r[0].parse::<f64>().unwrap() - t).abs() < 1e-9)
        .map(|r| r[col].parse().unwrap())
        .unwrap();
    let shown = attribute(&dom, "<body", "data-contact-forces").unwrap();
    let shown: f64 = shown.trim_matches(|c| c == '[' || c == ']').parse().unwrap();
    assert!(
        (shown - force).abs() < 1e-4 * force,
        "the page shows {shown} N, the run {force} N"
    );
    let view = attribute(&dom, "<canvas", "data-view").unwrap();
    let (scale, ox, oy) = (
        json_number(&view, "scale"),
        json_number(&view, "ox"),
        json_number(&view, "oy"),
    );
    let to_px = |p: [f64; 2]| (ox + scale * p[0], oy - scale * p[1]);
    let shot = tmp("cam-roller.png");
    browse(&browser, &url, size, &[&format!("--screenshot={}", shot.display())]);
    let png = Png::read(&shot);
    // The law's geometry: the pitch curve C(φ) = Y(φ) (sin φ, cos φ) in the cam's frame, its
    // outward normal N(φ), the profile C − R N; the cam turned by θ = ω t.
    let (rb, r, h, w) = (0.05, 0.02, 0.03, 4.0 * std::f64::consts::PI);
    let theta = w * t;
    let profile = |phi: f64| -> ([f64; 2], [f64; 2]) {
        let (y, yp) = (rb + r + 0.5 * h * (1.0 - phi.cos()), 0.5 * h * phi.sin());
        let tangent = [yp * phi.sin() + y * phi.cos(), yp * phi.cos() - y * phi.sin()];
        let len = tangent[0].hypot(tangent[1]);
        let n = [-tangent[1] / len, tangent[0] / len];
        let p = [y * phi.sin() - r * n[0], y * phi.cos() - r * n[1]];
        let turn = |v: [f64; 2]| {
            [
                theta.cos() * v[0] - theta.sin() * v[1],
                theta.sin() * v[0] + theta.cos() * v[1],
            ]
        };
        (turn(p), turn(n))
    };
    // The roller touches the profile at φ = θ (its centre on the pitch curve's point there).
    let (contact, normal) = profile(theta);
    let along = |d: f64| to_px([contact[0] + d * normal[0], contact[1] + d * normal[1]]);
    let magenta = hex("#e6007e");
    let (x, y) = along(0.02);
    assert!(
        png.has_color_near(x, y, 3, magenta),
        "no arrow 2 cm along the normal at ({x:.0}, {y:.0}) px"
    );
    let (x, y) = along(-0.02);
    assert!(
        !png.has_color_near(x, y, 3, magenta),
        "an arrow into the cam at ({x:.0}, {y:.0}) px"
    );
    let (far, _) = profile(theta + std::f64::consts::PI);
    let (x, y) = to_px(far);
    assert!(
        png.has_color_near(x, y, 1, hex("#1f77b4")),
        "no profile outline at ({x:.0}, {y:.0}) px"
    );
}
