//! Image I/O tests: PNG and EXR round trips, non-finite values, atomic writes,
//! value checks and rejected inputs.

use super::*;

fn test_image() -> Image {
    let mut img = Image::new(5, 3);
    for y in 0..3 {
        for x in 0..5 {
            let v = Vec3::new(x as f32 / 4.0, y as f32 / 2.0, 0.3 * (x + y) as f32 / 6.0);
            img.set(x, y, v);
        }
    }
    img
}

#[test]
fn png_round_trip_is_within_one_step_of_eight_bit_srgb() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("a.png");
    let img = test_image();
    write_image(&path, &img).expect("write png");
    let back = read_image(&path).expect("read png");
    assert_eq!((back.width, back.height), (5, 3));
    assert_eq!(img.pixels.len(), back.pixels.len());
    for (a, b) in img.pixels.iter().zip(&back.pixels) {
        for c in 0..3 {
            let (ea, eb) = (linear_to_srgb(a[c]), linear_to_srgb(b[c]));
            assert!((ea - eb).abs() <= 0.5 / 255.0 + 1e-6, "{a} vs {b}");
        }
    }
    // Row 0 is the top row in both.
    assert_eq!(back.get(0, 0), Vec3::ZERO);
    assert!(back.get(4, 2).x > 0.99);
}

#[test]
fn srgb_encoding_clamps_infinities_and_maps_nan_to_zero() {
    let white = linear_to_srgb(1.0);
    assert_eq!(linear_to_srgb(f32::INFINITY), white);
    assert_eq!(linear_to_srgb(f32::MAX), white);
    assert_eq!(linear_to_srgb(f32::NEG_INFINITY), 0.0);
    assert_eq!(linear_to_srgb(f32::MIN), 0.0);
    assert_eq!(linear_to_srgb(f32::NAN), 0.0);
    assert_eq!(linear_to_srgb(-f32::NAN), 0.0);
}

#[test]
fn png_clamps_infinities_and_maps_nan_to_zero() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("b.png");
    let mut img = Image::new(2, 1);
    img.set(0, 0, Vec3::new(f32::NAN, f32::INFINITY, f32::NEG_INFINITY));
    img.set(1, 0, Vec3::new(7.0, -3.0, 0.5));
    write_image(&path, &img).expect("write png");
    let back = read_image(&path).expect("read png");
    assert_eq!(back.get(0, 0), Vec3::new(0.0, 1.0, 0.0));
    assert_eq!((back.get(1, 0).x, back.get(1, 0).y), (1.0, 0.0));
    assert!((back.get(1, 0).z - 0.5).abs() < 0.01);
}

#[test]
fn exr_round_trip_is_exact_including_non_finite() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("c.exr");
    let mut img = test_image();
    img.set(1, 1, Vec3::new(1e6, -2.5, f32::INFINITY));
    write_image(&path, &img).expect("write exr");
    let back = read_image(&path).expect("read exr");
    assert_eq!(back, img);
}

#[test]
fn exr_bytes_depend_only_on_the_pixels() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut img = Image::new(300, 200);
    for y in 0..200 {
        for x in 0..300 {
            let v = ((x * 7 + y * 13) % 97) as f32 / 97.0;
            img.set(x, y, Vec3::new(v, 1.0 - v, v * v));
        }
    }
    let first = dir.path().join("first.exr");
    write_image(&first, &img).expect("write exr");
    let bytes = std::fs::read(&first).expect("read bytes");
    for i in 0..8 {
        let again = dir.path().join(format!("again{i}.exr"));
        write_image(&again, &img).expect("write exr");
        assert_eq!(
            std::fs::read(&again).expect("read bytes"),
            bytes,
            "write {i}"
        );
    }
}

#[test]
fn alpha_channels_are_ignored_on_read() {
    let dir = tempfile::tempdir().expect("temp dir");
    let png = dir.path().join("rgba.png");
    let file = std::fs::File::create(&png).expect("create");
    image::codecs::png::PngEncoder::new(file)
        .write_image(&[255, 0, 188, 7], 1, 1, image::ExtendedColorType::Rgba8)
        .expect("encode");
    let px = read_image(&png).expect("read rgba png").get(0, 0);
    assert!(
        (px.x - 1.0).abs() < 1e-6 && px.y == 0.0 && (px.z - 0.5).abs() < 0.003,
        "{px}"
    );
    let exr = dir.path().join("rgba.exr");
    exr::prelude::write_rgba_file(&exr, 2, 1, |x, _| (x as f32, 2.0, 3.0, 0.25)).expect("encode");
    let img = read_image(&exr).expect("read rgba exr");
    assert_eq!(
        img.pixels,
        vec![Vec3::new(0.0, 2.0, 3.0), Vec3::new(1.0, 2.0, 3.0)]
    );
}

#[test]
fn an_exr_declaring_too_many_pixels_is_rejected_before_allocating() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("huge.exr");
    write_image(&path, &test_image()).expect("write exr");
    // The data and display windows (box2i: x_min, y_min, x_max, y_max)
    // enlarged to 60001², 43 GB of pixels; the file stays 5x3.
    let mut bytes = std::fs::read(&path).expect("read bytes");
    let old: Vec<u8> = [0i32, 0, 4, 2]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let new: Vec<u8> = [0i32, 0, 60_000, 60_000]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let at: Vec<usize> = (0..bytes.len() - old.len())
        .filter(|&i| bytes[i..i + old.len()] == old[..])
        .collect();
    assert_eq!(at.len(), 2, "data and display windows");
    for i in at {
        bytes[i..i + new.len()].copy_from_slice(&new);
    }
    std::fs::write(&path, bytes).expect("write bytes");
    let err = read_image(&path).expect_err("too large").to_string();
    assert!(
        err.contains("huge.exr") && err.contains("declares a 60001x60001 layer"),
        "{err}"
    );
}

#[test]
fn check_values_names_the_first_pixel_outside_the_range() {
    let path = Path::new("t.exr");
    let mut img = test_image();
    assert!(check_values(path, &img, 1.0).is_ok());
    img.set(3, 1, Vec3::new(0.5, f32::NAN, 2.0));
    img.set(4, 2, Vec3::new(-1.0, 0.0, 0.0));
    let err = check_values(path, &img, f32::INFINITY).expect_err("nan");
    assert_eq!(
        err.to_string(),
        "t.exr: pixel (3, 1) has g = NaN; expected finite values >= 0"
    );
    img.set(3, 1, Vec3::new(0.5, 0.5, 2.0));
    let err = check_values(path, &img, 1.0).expect_err("above one");
    assert_eq!(
        err.to_string(),
        "t.exr: pixel (3, 1) has b = 2; expected finite values in [0, 1]"
    );
    let err = check_values(path, &img, f32::INFINITY).expect_err("negative");
    assert!(err.to_string().contains("pixel (4, 2) has r = -1"), "{err}");
}

#[test]
fn atomic_write_replaces_the_file_and_leaves_no_temporary_behind() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("d.exr");
    std::fs::write(&path, b"old").expect("seed");
    write_image(&path, &test_image()).expect("write exr");
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .expect("list")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("d.exr")]);
    assert_eq!(read_image(&path).expect("read"), test_image());
}

#[test]
fn png_bytes_are_written_as_given_and_a_wrong_length_is_an_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("plot.png");
    let rgb = [0u8, 128, 255, 255, 255, 255];
    let color = image::ExtendedColorType::Rgb8;
    write_png_bytes(&path, 2, 1, color, &rgb).expect("write");
    let back = read_image(&path).expect("read");
    let expect = |v: u8| srgb_to_linear(f32::from(v) / 255.0);
    assert_eq!(
        back.get(0, 0),
        Vec3::new(expect(0), expect(128), expect(255))
    );
    assert_eq!(back.get(1, 0), Vec3::ONE);
    let err = write_png_bytes(&path, 2, 2, color, &rgb).expect_err("short buffer");
    assert!(err.to_string().contains("need 12 bytes, got 6"), "{err}");
    assert_eq!(std::fs::read_dir(dir.path()).expect("list").count(), 1);
}

#[test]
fn unknown_extensions_are_rejected_and_nothing_is_written() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("e.jpg");
    assert!(write_image(&path, &test_image()).is_err());
    assert!(read_image(&path).is_err());
    assert_eq!(std::fs::read_dir(dir.path()).expect("list").count(), 0);
}
