// Texture-space diffusion's blur (Gosselin et al. 2004): a 12-tap Poisson disc plus the centre,
// the disc scaled per texel by the kernel size stored in the light map's alpha
// (radius = a * k + b texels), between the light maps; with the profile's Gaussians (d'Eon and
// Luebke 2007) each pass also scales its result and adds the kept irradiance, weighted per
// channel (src/skin/tsd.rs). The first pass also dilates:
// a texel with an unwritten tap (alpha 1, the clear value) takes the tap of smallest kernel size
// instead, so bilinear fetches across UV seams read lit texels, not black.

// The blur's uniforms (`BlurUniforms` in src/pass/blur/mod.rs).
struct BlurUniforms {
    // 1 / light-map size.
    inv_size: vec2<f32>,
    // Kernel radius in texels = a * k + b for the stored kernel size k.
    a: f32,
    b: f32,
    // 1: this pass dilates.
    dilate: u32,
    // The variance per axis (texels^2) a radius of 1 stands for: the disc's mean over u and v.
    tap_variance: f32,
    // The mean of the 13 taps (centre included), in radii.
    tap_mean: vec2<f32>,
    // Scales the blurred source per channel.
    source_scale: vec4<f32>,
    // Weight of the kept irradiance (light map B) added after the blur, per channel.
    irradiance_weight: vec4<f32>,
    // The disc's own variance along u and v for radius 1 (it is not isotropic).
    axis_variance: vec2<f32>,
    pad0: f32,
    pad1: f32,
    // Bilinear pass radius along (u, v) for variances 0 to RADIUS_TABLE_MAX_VARIANCE texels^2,
    // two entries per vec4 (src/skin/tsd.rs, `radius_table`).
    radius_table: array<vec4<f32>, 32>,
}

const RADIUS_TABLE_LEN: u32 = 64u;
const RADIUS_TABLE_MAX_VARIANCE: f32 = 4.0;

@group(0) @binding(0) var<uniform> blur: BlurUniforms;
@group(0) @binding(1) var source: texture_2d<f32>;
@group(0) @binding(2) var source_sampler: sampler;
@group(0) @binding(3) var irradiance: texture_2d<f32>;
// Per texel, the kernel's widening along u and v (the light-map pass's stretch map).
@group(0) @binding(4) var stretch: texture_2d<f32>;

const POISSON: array<vec2<f32>, 12> = array<vec2<f32>, 12>(
    vec2<f32>(-0.326212, -0.40581),
    vec2<f32>(-0.840144, -0.07358),
    vec2<f32>(-0.695914, 0.457137),
    vec2<f32>(-0.203345, 0.620716),
    vec2<f32>(0.96234, -0.194983),
    vec2<f32>(0.473434, -0.480026),
    vec2<f32>(0.519456, 0.767022),
    vec2<f32>(0.185461, -0.893124),
    vec2<f32>(0.507431, 0.064425),
    vec2<f32>(0.89642, 0.412458),
    vec2<f32>(-0.32194, -0.932615),
    vec2<f32>(-0.791559, -0.59771),
);

struct FullScreen {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

// One triangle covering the target; uv (0, 0) at the top-left.
@vertex
fn vs_full_screen(@builtin(vertex_index) index: u32) -> FullScreen {
    let x = f32((index << 1u) & 2u);
    let y = f32(index & 2u);
    var out: FullScreen;
    out.clip = vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
    out.uv = vec2<f32>(x, y);
    return out;
}

// The bilinear pass's radius along `axis` that adds `variance` texels^2 along it, the sampler's
// own spread included (`radius_for_variance` in src/skin/tsd.rs, which tests it): a tap at
// offset o mixes two texels, adding f (1 - f) for f the fraction of o. Below a texel that share
// grows linearly with the radius and is most of the pass's variance, so it is read from the
// table; above the table it averages 1/6.
fn axis_radius(variance: f32, axis: u32) -> f32 {
    if variance >= RADIUS_TABLE_MAX_VARIANCE {
        return sqrt((variance - 1.0 / 6.0) / blur.axis_variance[axis]);
    }
    let x = max(variance, 0.0) / RADIUS_TABLE_MAX_VARIANCE * f32(RADIUS_TABLE_LEN - 1u);
    let i = min(u32(x), RADIUS_TABLE_LEN - 2u);
    let t = x - f32(i);
    let lo = blur.radius_table[i / 2u][(i % 2u) * 2u + axis];
    let j = i + 1u;
    let hi = blur.radius_table[j / 2u][(j % 2u) * 2u + axis];
    return mix(lo, hi, t);
}

// The disc's radius in texels along u and v for the variance a nominal radius stands for, so
// that the passes add up to that variance whatever their count. The dilating pass's nearest
// taps move by their rounding instead, variance 1/12 on average.
fn disc_radius(nominal: vec2<f32>) -> vec2<f32> {
    let variance = nominal * nominal * blur.tap_variance;
    if blur.dilate == 1u {
        return sqrt(max(variance - 1.0 / 12.0, vec2<f32>(0.0)) / blur.axis_variance);
    }
    return vec2<f32>(axis_radius(variance.x, 0u), axis_radius(variance.y, 1u));
}

@fragment
fn fs_blur(input: FullScreen) -> @location(0) vec4<f32> {
    let centre = textureSampleLevel(source, source_sampler, input.uv, 0.0);
    // The isotropic radius in texels, widened along u and v where a texel spans fewer mm there
    // than the light map's mean stretch assumed.
    let widening = textureSampleLevel(stretch, source_sampler, input.uv, 0.0).rg;
    let radius = blur.inv_size * disc_radius((min(centre.a, 0.999) * blur.a + blur.b) * widening);
    // The 13 taps (the centre and the disc) moved by minus their mean, so that a pass blurs
    // without shifting the map (Gosselin's disc is off centre by 0.1 radius along v).
    var sum = vec3<f32>(0.0);
    var written_sum = vec3<f32>(0.0);
    var written = 0.0;
    var smallest = centre;
    for (var tap = 0u; tap < 13u; tap++) {
        var offset = -blur.tap_mean;
        if tap > 0u {
            offset += POISSON[tap - 1u];
        }
        let s = textureSampleLevel(source, source_sampler, input.uv + offset * radius, 0.0);
        sum += s.rgb;
        if s.a < 1.0 {
            written_sum += s.rgb;
            written += 1.0;
        }
        if s.a < smallest.a {
            smallest = s;
        }
    }
    if blur.dilate == 1u {
        if centre.a >= 1.0 {
            // Unwritten texel: copy the nearest-in-kernel written tap (dilation), or stay unwritten.
            return smallest;
        }
        // A written texel next to unwritten ones averages only what was written (the chapter's
        // "more complicated scheme"; its own code copies one tap instead).
        return vec4<f32>(written_sum / max(written, 1.0), centre.a);
    }
    // Every pass averages only the written taps: the texels outside the charts hold no light,
    // and averaging them in would darken the charts' borders a little more with every pass.
    var mean = sum / 13.0;
    if centre.a < 1.0 && written > 0.0 {
        mean = written_sum / written;
    }
    let added = textureSampleLevel(irradiance, source_sampler, input.uv, 0.0).rgb;
    return vec4<f32>(blur.source_scale.rgb * mean + blur.irradiance_weight.rgb * added, centre.a);
}
