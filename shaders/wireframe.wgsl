// The wireframe: scene edges as a line list, projected with the view-projection matrix
// built from the same frame constants the ray tracer's primary rays come from
// (`src/view/wireframe.rs::view_projection`, whose `project` is this vertex stage on
// the CPU).

struct Frame {
    view_proj: mat4x4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return frame.view_proj * vec4<f32>(position, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return frame.color;
}
