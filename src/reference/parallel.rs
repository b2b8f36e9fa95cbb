//! Spreading per-pixel CPU oracle work over all cores.

/// `f(p)` for every pixel index `p` of a row-major `width`×`height` image,
/// bands of rows on separate threads.
pub fn per_pixel<T: Send + Clone + Default>(
    width: usize,
    height: usize,
    f: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    let mut out = vec![T::default(); width * height];
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let band = (height.div_ceil(threads).max(1) * width).max(1);
    let f = &f;
    std::thread::scope(|s| {
        for (b, chunk) in out.chunks_mut(band).enumerate() {
            s.spawn(move || {
                for (i, v) in chunk.iter_mut().enumerate() {
                    *v = f(b * band + i);
                }
            });
        }
    });
    out
}

/// `f(x, y, texel)` for every texel of a row-major G-buffer of the image `params`
/// describes, spread as [`per_pixel`]; the shadow oracles' common loop.
///
/// # Panics
///
/// When `gbuffer` does not hold `width · height` texels (a caller bug).
pub fn per_texel<T: Send + Clone + Default>(
    gbuffer: &[crate::contract::layout::GBufferTexel],
    params: &crate::contract::layout::ShadowParams,
    f: impl Fn(u32, u32, &crate::contract::layout::GBufferTexel) -> T + Sync,
) -> Vec<T> {
    let (w, h) = (params.width as usize, params.height as usize);
    assert_eq!(
        gbuffer.len(),
        w * h,
        "G-buffer size does not match the parameters"
    );
    per_pixel(w, h, |p| f((p % w) as u32, (p / w) as u32, &gbuffer[p]))
}
