//! Several lights: one frame per light over one G-buffer (`Renderer::render_lights`), each
//! the frame a one-light render gives, and the image of all of them the sum of the
//! one-light images.

use crate::support;

use glam::Vec3;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{Ambient, FrameSettings, GpuScene, Renderer, image_of_lights};
use penumbra::scene::view::QuadLight;
use support::gpu::{ctx, embedded, variants};

#[test]
fn two_lights_give_the_sum_of_two_one_light_renders() {
    let (scene, view) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let mut second = view;
    second.light = QuadLight {
        corner: Vec3::new(2.0, 5.0, -3.0),
        edge_u: Vec3::new(1.0, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, 1.5),
        color: Vec3::new(1.0, 0.6, 0.3),
        intensity: 20.0,
    };
    let mut settings = FrameSettings::new(64, 48);
    settings.refine = true;
    for variant in variants() {
        let renderer = Renderer::new(ctx(), Some(variant)).unwrap();
        let frames = renderer
            .render_lights(ctx(), &gpu_scene, &[view, second], &settings, &mut |_, _, _| {})
            .unwrap();
        assert_eq!(frames.len(), 2);
        let alone = [&view, &second].map(|v| renderer.render(ctx(), &gpu_scene, v, &settings).unwrap());
        for (i, (frame, one)) in frames.iter().zip(&alone).enumerate() {
            // The same kernels on the same G-buffer: the same bits.
            assert_eq!(frame.masks, one.masks, "{variant}: light {i}'s masks");
            assert_eq!(
                frame.filtered, one.filtered,
                "{variant}: light {i}'s filtered irradiance"
            );
            assert_eq!(
                frame.refined, one.refined,
                "{variant}: light {i}'s refined pixels"
            );
        }
        assert!(frames[0].timed_ms("primary").is_some() == ctx().info.has_timestamps);
        assert!(
            frames[1].timed_ms("primary").is_none(),
            "one primary pass, in the first frame"
        );

        let both = image_of_lights(&frames, &Ambient::NONE);
        let [a, b] = alone.map(|f| f.image(&Ambient::NONE));
        let lit_by_second = support::assert_image_is_sum(&both, &a, &b, &variant.to_string());
        assert!(
            lit_by_second * 10 > both.len(),
            "{variant}: the second light lights only {lit_by_second} pixels"
        );
    }
}
