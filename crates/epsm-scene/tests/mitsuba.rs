//! Mitsuba 3 XML scenes map as `docs/interop.md` documents: parameters and
//! settings, fields of view, named metals and IORs, material naming, shapes
//! (sphere placement, PLY and OBJ files), the environment map's rotation,
//! and skipped elements reported as located warnings.

use std::path::Path;

use epsm_render::film::Image;
use epsm_render::lights::Background;
use epsm_render::materials::{Bsdf, Conductor, Dielectric};
use epsm_render::scene::Surface;
use epsm_scene::image_io::write_image;
use epsm_scene::import::mitsuba::from_str;
use epsm_scene::{Loaded, shapes};
use glam::{DAffine3, DVec3, Vec3};

/// Loads a scene made of `sensor` and `body` from `dir/scene.xml`.
fn load(dir: &Path, sensor: &str, body: &str) -> Loaded {
    let text = format!(
        "<scene version=\"3.0.0\">\n<default name=\"spp\" value=\"12\"/>\n{sensor}\n{body}\n</scene>\n"
    );
    from_str(&text, &dir.join("scene.xml")).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

const SENSOR: &str = r#"<sensor type="perspective"><float name="fov" value="40"/>
    <film type="hdrfilm"><integer name="width" value="20"/><integer name="height" value="10"/></film></sensor>"#;

#[test]
fn parameters_fov_axes_and_integrator_settings_map() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sensor = r#"<sensor type="perspective">
        <float name="fov" value="90"/>
        <sampler type="stratified"><integer name="sample_count" value="$spp"/><integer name="seed" value="3"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="32"/></film>
    </sensor>
    <integrator type="path"><integer name="max_depth" value="5"/></integrator>"#;
    let p = load(dir.path(), sensor, r#"<shape type="cube"/>"#).parts;
    assert_eq!(
        (
            p.settings.spp,
            p.settings.seed,
            p.settings.max_depth,
            p.settings.rr_depth
        ),
        (12, 3, 4, 5)
    );
    // fov 90° across x at aspect 2: tan(fov_y / 2) = tan(45°) / 2.
    assert!((p.camera.fov_y - 2.0 * 0.5f64.atan()).abs() < 1e-12);
    assert_eq!((p.camera.width, p.camera.height), (64, 32));
    assert!(
        p.camera.forward.abs_diff_eq(DVec3::Z, 1e-12),
        "identity to_world looks along +z"
    );
    for (axis, expected) in [
        ("y", 90.0f64),
        ("smaller", 90.0),
        ("larger", 2.0 * 0.5f64.atan().to_degrees()),
    ] {
        let s = sensor.replace(
            r#"value="90"/>"#,
            &format!(r#"value="90"/><string name="fov_axis" value="{axis}"/>"#),
        );
        let p = load(dir.path(), &s, r#"<shape type="cube"/>"#).parts;
        assert!(
            (p.camera.fov_y.to_degrees() - expected).abs() < 1e-9,
            "{axis}"
        );
    }
    let p = load(dir.path(), SENSOR, r#"<shape type="cube"/>"#).parts;
    assert_eq!(
        (p.settings.spp, p.settings.max_depth),
        (4, 1024),
        "Mitsuba's defaults"
    );
}

#[test]
fn bsdfs_map_named_metals_iors_twosided_and_names() {
    let dir = tempfile::tempdir().expect("temp dir");
    let body = r#"
        <bsdf type="twosided" id="paper"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf></bsdf>
        <bsdf type="dielectric" id="water"><string name="int_ior" value="water"/><float name="ext_ior" value="1"/></bsdf>
        <shape type="cube" id="a"><ref id="paper"/></shape>
        <shape type="cube" id="b"><bsdf type="conductor"><string name="material" value="Au"/><rgb name="specular_reflectance" value="0.5"/></bsdf></shape>
        <shape type="cube" id="c"><ref name="bsdf" id="water"/></shape>
        <shape type="cube" id="d"/>
        <shape type="cube"><ref id="paper"/></shape>"#;
    let p = load(dir.path(), SENSOR, body).parts;
    let m = |i: usize| &p.materials[p.objects[i].material as usize];
    assert_eq!((m(0).name.as_str(), m(0).two_sided), ("paper", true));
    assert_eq!(m(1).name, "b_bsdf");
    let Bsdf::Conductor(Conductor { tint }) = m(1).bsdf else {
        panic!("gold is a conductor")
    };
    assert!(
        tint.abs_diff_eq(Vec3::new(0.5, 0.391, 0.172), 1e-6),
        "{tint}"
    );
    assert_eq!(m(2).bsdf, Bsdf::Dielectric(Dielectric { ior: 1.333 }));
    assert_eq!((m(3).name.as_str(), m(3).two_sided), ("default", false));
    assert_eq!(p.objects[4].name, "shape4");
    assert_eq!(
        p.objects[4].material, p.objects[0].material,
        "a referenced BSDF is one material"
    );
    assert_eq!(p.materials.len(), 4);
}

#[test]
fn shapes_place_spheres_and_read_ply_and_obj_files() {
    let dir = tempfile::tempdir().expect("temp dir");
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
               element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    std::fs::write(dir.path().join("tri.ply"), ply).expect("write ply");
    std::fs::write(
        dir.path().join("tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n",
    )
    .expect("write obj");
    let body = r#"
        <shape type="sphere" id="ball"><point name="center" x="1" y="2" z="3"/><float name="radius" value="0.5"/></shape>
        <shape type="sphere" id="lamp"><emitter type="area"/></shape>
        <shape type="sphere" id="inward"><boolean name="flip_normals" value="true"/></shape>
        <shape type="ply" id="tri"><string name="filename" value="tri.ply"/>
            <transform name="to_world"><translate x="5"/></transform><boolean name="flip_normals" value="true"/></shape>
        <shape type="obj" id="flat"><string name="filename" value="tri.obj"/><boolean name="face_normals" value="true"/>
            <emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>"#;
    let p = load(dir.path(), SENSOR, body).parts;
    let ball = &p.objects[0];
    let expected = DAffine3::from_translation(DVec3::new(1.0, 2.0, 3.0))
        * DAffine3::from_scale(DVec3::splat(0.5));
    assert!(ball.world_from_object.abs_diff_eq(expected, 1e-15));
    assert_eq!((ball.surface, ball.mesh.len()), (Surface::Sphere, 0));
    // Exact spheres neither emit nor flip: those stay icospheres.
    let [lamp, inward] = [&p.objects[1], &p.objects[2]];
    assert_eq!(
        (lamp.surface, lamp.emission),
        (Surface::Mesh, Some(Vec3::ONE))
    );
    assert_eq!(lamp.mesh.len(), shapes::sphere(4).len());
    assert_eq!(
        (inward.surface, inward.mesh.len()),
        (Surface::Mesh, shapes::sphere(4).len())
    );
    assert_eq!(
        p.objects[3].mesh.indices,
        vec![[0, 2, 1]],
        "flip_normals reverses the winding"
    );
    assert_eq!(
        p.objects[3].world_from_object.translation,
        DVec3::new(5.0, 0.0, 0.0)
    );
    assert!(
        p.objects[4].mesh.normals.is_empty(),
        "face_normals drops vertex normals"
    );
    assert_eq!(p.objects[4].emission, Some(Vec3::splat(3.0)));
}

#[test]
fn envmap_rotation_about_y_matches_mitsubas_lookup() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (w, h) = (16, 8);
    let pixels = (0..w * h)
        .map(|i| Vec3::new((i % w) as f32, (i / w) as f32, 1.0))
        .collect();
    write_image(
        &dir.path().join("sky.exr"),
        &Image {
            width: w,
            height: h,
            pixels,
        },
    )
    .expect("write exr");
    let body = r#"<shape type="cube"/><emitter type="envmap"><string name="filename" value="sky.exr"/>
        <float name="scale" value="2"/><transform name="to_world"><rotate y="1" angle="60"/></transform></emitter>"#;
    let p = load(dir.path(), SENSOR, body).parts;
    let Background::EnvMap(_) = &p.background else {
        panic!("expected an environment map")
    };
    let world_from_map = DAffine3::from_rotation_y(60f64.to_radians());
    for d in [
        DVec3::new(0.3, 0.2, -0.9),
        DVec3::new(-0.7, -0.4, 0.1),
        DVec3::new(0.5, 0.6, 0.6),
    ] {
        let d = d.normalize();
        // Mitsuba: local = to_world⁻¹ d, u = atan2(x, −z)/2π + ½, v = acos(y)/π.
        let l = world_from_map.inverse().transform_vector3(d);
        let u = (l.x.atan2(-l.z) / std::f64::consts::TAU + 0.5).rem_euclid(1.0);
        let v = l.y.acos() / std::f64::consts::PI;
        let (x, y) = ((u * w as f64) as u32, (v * h as f64) as u32);
        let expected = Vec3::new(x as f32, y as f32, 1.0) * 2.0;
        assert_eq!(p.background.eval(d.as_vec3()), expected, "direction {d}");
    }
}

#[test]
fn skippable_elements_are_located_warnings() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sensor = SENSOR.replace(
        "</film>",
        "<rfilter type=\"gaussian\"/></film><float name=\"near_clip\" value=\"0.1\"/>",
    );
    // A box filter is epsm's own: no warning.
    let boxed = SENSOR.replace("</film>", "<rfilter type=\"box\"/></film>");
    let quiet = load(dir.path(), &boxed, r#"<shape type="cube"/>"#);
    assert!(quiet.warnings.is_empty(), "{:?}", quiet.warnings);
    let loaded = load(dir.path(), &sensor, r#"<shape type="cube"/>"#);
    let fields: Vec<(&str, Option<usize>)> = loaded
        .warnings
        .iter()
        .map(|w| (w.field.as_str(), w.line))
        .collect();
    assert_eq!(
        fields,
        [
            ("scene.sensor[0].film[0].rfilter[0]", Some(4)),
            ("scene.sensor[0].near_clip", Some(4))
        ]
    );
}
