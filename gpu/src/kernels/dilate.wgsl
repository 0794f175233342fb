// One axis of a cube dilation of a cell mask (the active region's classification, see
// classify.wgsl): a cell is set when a cell within `radius` of it along `axis` (0 x, 1 y,
// 2 z) is set in `src`. Three in turn grow the mask by a cube. CPU twin: `region::dilate`.

struct Dilate { axis: u32, radius: u32, pad0: u32, pad1: u32 }

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<uniform> dil: Dilate;
@group(0) @binding(2) var<storage, read> src: array<u32>;
@group(0) @binding(3) var<storage, read_write> dst: array<u32>;

@compute @workgroup_size(64)
fn dilate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c >= prm.n_cells) { return; }
    let dims = vec3<u32>(prm.dim_x, prm.dim_y, prm.dim_z);
    let stride = vec3<u32>(prm.dim_y * prm.dim_z, prm.dim_z, 1u);
    let a = dil.axis;
    let i = c / stride[a] % dims[a];
    let base = c - i * stride[a];
    let lo = select(0u, i - dil.radius, i >= dil.radius);
    let hi = min(i + dil.radius, dims[a] - 1u);
    var hit = 0u;
    for (var j = lo; j <= hi; j++) {
        if (src[base + j * stride[a]] != 0u) {
            hit = 1u;
            break;
        }
    }
    dst[c] = hit;
}
