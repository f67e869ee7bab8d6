// Flat-coloured mesh with two-sided Lambert shading, and a line pass for the wireframe.

struct Uniforms {
    view_proj: mat4x4<f32>,
    // xyz: direction towards the light (view space follows the camera), w: ambient term.
    light: vec4<f32>,
    // rgb: wireframe colour, a: unused.
    line_color: vec4<f32>,
};

@group(0) @binding(0) var<uniform> u: Uniforms;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec3<f32>,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = u.view_proj * vec4<f32>(v.position, 1.0);
    out.normal = v.normal;
    out.color = v.color;
    return out;
}

@fragment
fn fs_shaded(v: VertexOut) -> @location(0) vec4<f32> {
    let n = normalize(v.normal);
    // Two-sided: open meshes show their back faces lit too.
    let diffuse = abs(dot(n, normalize(u.light.xyz)));
    let shade = u.light.w + (1.0 - u.light.w) * diffuse;
    return vec4<f32>(v.color * shade, 1.0);
}

@fragment
fn fs_lines(v: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(u.line_color.rgb, 1.0);
}
