//! GPU smoke tests: adapter choice, buffers, readback, timestamps and the shader assembler,
//! end to end on the adapter `GpuContext` picks (lavapipe where there is no GPU).
//!
//! With no adapter these tests fail with the error's advice; they never pass silently.

use penumbra::Error;
use penumbra::contract::layout::BvhNode;
use penumbra::gpu::{GpuContext, GpuOptions, GpuTimer, empty_storage_buffer, read_buffer, storage_buffer};
use penumbra::shaders;

use glam::Vec3;

/// The context every test uses; prints the adapter line first so the log shows what ran.
fn context() -> GpuContext {
    match GpuContext::new(&GpuOptions::default()) {
        Ok(ctx) => {
            println!("adapter: {}", ctx.info);
            ctx
        }
        Err(e) => panic!("no GPU context: {e}"),
    }
}

/// A bind group layout of read-only storage buffers followed by one read-write buffer.
fn storage_layout(ctx: &GpuContext, n_read_only: u32) -> wgpu::BindGroupLayout {
    let entry = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let mut entries: Vec<_> = (0..n_read_only).map(|b| entry(b, true)).collect();
    entries.push(entry(n_read_only, false));
    ctx.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("smoke test"),
            entries: &entries,
        })
}

/// A compute pipeline for entry point `main` of `wgsl` with an explicit layout
/// (with `layout: None` wgpu would drop bindings the kernel does not use).
fn pipeline(ctx: &GpuContext, wgsl: &str, layout: &wgpu::BindGroupLayout) -> wgpu::ComputePipeline {
    ctx.capture_errors("smoke test pipeline", || {
        let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("smoke test"),
            source: wgpu::ShaderSource::Wgsl(wgsl.into()),
        });
        let pipeline_layout = ctx
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("smoke test"),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
        ctx.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("smoke test"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            })
    })
    .unwrap_or_else(|e| panic!("{e}"))
}

fn bind_group(
    ctx: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("smoke test"),
        layout,
        entries: &entries,
    })
}

#[test]
fn selftest_kernel_copies_node_counts() {
    let ctx = context();
    const N_NODES: u32 = 300; // not a multiple of the workgroup size: the bounds check matters
    let nodes: Vec<BvhNode> = (0..N_NODES)
        .map(|i| BvhNode {
            bmin: Vec3::splat(i as f32),
            first: 2 * i + 1,
            bmax: Vec3::splat(i as f32 + 1.0),
            count: (i * 7919) % 13,
        })
        .collect();
    let nodes_buf = storage_buffer(&ctx, "nodes", &nodes, wgpu::BufferUsages::empty()).unwrap();
    let counts_buf = empty_storage_buffer(
        &ctx,
        "counts",
        u64::from(N_NODES) * 4,
        wgpu::BufferUsages::COPY_SRC,
    )
    .unwrap();

    let wgsl = shaders::assemble("gpu_selftest", &[]).unwrap_or_else(|e| panic!("{e}"));
    let layout = storage_layout(&ctx, 1);
    let pipeline = pipeline(&ctx, &wgsl, &layout);
    let bind_group = bind_group(&ctx, &layout, &[&nodes_buf, &counts_buf]);

    let mut timer = GpuTimer::new(&ctx, 1);
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("selftest"),
        });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("selftest"),
            timestamp_writes: timer.pass_writes("selftest"),
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(N_NODES.div_ceil(64), 1, 1);
    }
    timer.resolve(&mut encoder);
    ctx.queue.submit([encoder.finish()]);

    let gpu: Vec<u32> = read_buffer(&ctx, &counts_buf, 0..u64::from(N_NODES) * 4).unwrap();
    let cpu: Vec<u32> = nodes.iter().map(|n| n.count).collect();
    assert_eq!(gpu, cpu, "GPU counts (left) differ from the CPU's (right)");

    let timings = timer.read(&ctx).unwrap();
    if ctx.info.has_timestamps {
        assert_eq!(timings.len(), 1, "one timed pass: {timings:?}");
        let (label, ms) = &timings[0];
        println!("timestamp: {label} took {ms:.4} ms");
        assert_eq!(label, "selftest");
        assert!(ms.is_finite() && *ms >= 0.0, "pass time {ms} ms");
    } else {
        println!("timestamp: not supported by this adapter");
        assert!(timings.is_empty());
    }
}

#[test]
fn subgroup_size_is_within_the_reported_range() {
    let ctx = context();
    if !ctx.info.has_subgroups {
        println!("subgroups: not supported by this adapter; nothing to check");
        return;
    }
    const WGSL: &str = "
        @group(0) @binding(0) var<storage, read_write> sizes: array<u32>;
        @compute @workgroup_size(64)
        fn main(@builtin(local_invocation_index) ix: u32, @builtin(subgroup_size) sg_size: u32) {
            sizes[ix] = sg_size;
        }";
    shaders::validate(WGSL).unwrap_or_else(|e| panic!("{e}"));
    let sizes_buf = empty_storage_buffer(&ctx, "sizes", 64 * 4, wgpu::BufferUsages::COPY_SRC).unwrap();
    let layout = storage_layout(&ctx, 0);
    let pipeline = pipeline(&ctx, WGSL, &layout);
    let bind_group = bind_group(&ctx, &layout, &[&sizes_buf]);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let sizes: Vec<u32> = read_buffer(&ctx, &sizes_buf, 0..64 * 4).unwrap();
    println!("subgroup_size seen by a 64-wide workgroup: {}", sizes[0]);
    for &size in &sizes {
        assert!(
            (ctx.info.subgroup_min_size..=ctx.info.subgroup_max_size).contains(&size),
            "subgroup size {size} outside the adapter's {}..{}",
            ctx.info.subgroup_min_size,
            ctx.info.subgroup_max_size
        );
    }
}

#[test]
fn oversized_buffers_are_errors_not_panics() {
    let ctx = context();
    let limit = ctx.info.max_storage_buffer_binding_size;
    match empty_storage_buffer(&ctx, "huge", limit + 4, wgpu::BufferUsages::empty()) {
        Err(Error::BufferTooLarge {
            what,
            bytes,
            limit: l,
        }) => {
            assert_eq!(what, "huge");
            assert!(bytes > l, "{bytes} > {l}");
        }
        other => panic!("expected BufferTooLarge, got {other:?}"),
    }
    // A data-backed buffer over the limit too, where the limit is small enough to allocate.
    if limit <= 256 << 20 {
        let data = vec![0u32; (limit / 4 + 1) as usize];
        let err = storage_buffer(&ctx, "too many triangles", &data, wgpu::BufferUsages::empty()).unwrap_err();
        println!("error: {err}");
        assert!(matches!(err, Error::BufferTooLarge { ref what, .. } if what == "too many triangles"));
    }
    // An empty slice still gives a bindable buffer.
    let empty = storage_buffer::<u32>(&ctx, "empty", &[], wgpu::BufferUsages::empty()).unwrap();
    assert!(empty.size() >= 16);
}

#[test]
fn bad_readback_ranges_are_errors() {
    let ctx = context();
    let buf = storage_buffer(&ctx, "small", &[1u32, 2, 3, 4], wgpu::BufferUsages::COPY_SRC).unwrap();
    assert!(read_buffer::<u32>(&ctx, &buf, 0..32).is_err(), "past the end");
    assert!(read_buffer::<u32>(&ctx, &buf, 2..6).is_err(), "misaligned");
    assert!(
        read_buffer::<[u32; 3]>(&ctx, &buf, 0..8).is_err(),
        "not whole elements"
    );
    assert_eq!(read_buffer::<u32>(&ctx, &buf, 4..12).unwrap(), [2, 3]);
    let no_copy = storage_buffer(&ctx, "no copy", &[1u32], wgpu::BufferUsages::empty()).unwrap();
    assert!(read_buffer::<u32>(&ctx, &no_copy, 0..4).is_err(), "no COPY_SRC");
}

#[test]
fn unknown_adapter_lists_the_available_ones() {
    let err = GpuContext::new(&GpuOptions {
        adapter: Some("no-such-adapter".into()),
        ..GpuOptions::default()
    })
    .expect_err("no adapter is called no-such-adapter");
    println!("error: {err}");
    match err {
        Error::AdapterNotFound { wanted, available } => {
            assert_eq!(wanted, "no-such-adapter");
            assert!(
                !available.is_empty(),
                "no adapters at all; install a Vulkan driver (apt-get install mesa-vulkan-drivers)"
            );
        }
        other => panic!("expected AdapterNotFound, got {other:?}"),
    }
}

#[test]
fn adapter_by_index_and_by_name() {
    let first = GpuContext::new(&GpuOptions {
        adapter: Some("0".into()),
        ..GpuOptions::default()
    })
    .unwrap_or_else(|e| panic!("adapter 0: {e}"));
    println!("adapter 0: {}", first.info);
    // Any part of the name, in any case.
    let part: String = first.info.name.chars().take(4).collect::<String>().to_uppercase();
    let by_name = GpuContext::new(&GpuOptions {
        adapter: Some(part.clone()),
        ..GpuOptions::default()
    })
    .unwrap_or_else(|e| panic!("adapter named {part:?}: {e}"));
    assert!(by_name.info.name.to_uppercase().contains(&part));
    let err = GpuContext::new(&GpuOptions {
        adapter: Some("999".into()),
        ..GpuOptions::default()
    })
    .expect_err("there are not 1000 adapters");
    assert!(matches!(err, Error::AdapterNotFound { .. }), "{err:?}");
}

/// A timer asked to time more passes than it holds fails its read (naming both counts)
/// instead of returning timings that silently leave passes out; the next frame's read
/// works again.
#[test]
fn more_timed_passes_than_the_timer_holds_is_an_error() {
    let ctx = context();
    if !ctx.info.has_timestamps {
        panic!(
            "this test needs an adapter with timestamp queries; {} has none",
            ctx.info.name
        );
    }
    let record = |timer: &mut GpuTimer, passes: usize| {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        for i in 0..passes {
            let _pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("empty"),
                timestamp_writes: timer.pass_writes(&format!("pass {i}")),
            });
        }
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
    };
    let mut timer = GpuTimer::new(&ctx, 2);
    record(&mut timer, 3);
    let err = timer.read(&ctx).unwrap_err();
    assert!(
        matches!(err, penumbra::Error::InvalidValue { .. }) && err.to_string().contains("timed passes = 3"),
        "{err}"
    );
    record(&mut timer, 2);
    assert_eq!(
        timer.read(&ctx).unwrap().len(),
        2,
        "a read after the failed one works"
    );
}
