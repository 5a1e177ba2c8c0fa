//! The GPU's lookup in a pre-integration table (`render_core::table_texture`: the texture,
//! its sampler and the shaders' `table_coord`) against the CPU's `Table3d::sample` and
//! `Table2d::sample`, at random points of tables of random entries.

use render_core::gpu::MemoryLedger;
use render_core::preintegration::{Table2d, Table3d};
use render_core::table_texture::{TableTexture, TABLE_WGSL};
use render_core::Gpu;

struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

const SAMPLER: &str = r#"
@group(0) @binding(0) var table: texture_3d<f32>;
@group(0) @binding(1) var table_sampler: sampler;
// x: s_front, y: s_back, z: length in units of the table's longest; w: unused
@group(0) @binding(2) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> samples: array<vec4<f32>>;
// x: entries per scalar axis, y: entries on the length axis (1: a 2D table)
@group(0) @binding(4) var<storage, read> sizes: vec4<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&points) {
        return;
    }
    let p = points[id.x];
    var w = 0.5;
    if sizes.y > 1.0 {
        w = table_coord(p.z, sizes.y);
    }
    let uvw = vec3<f32>(table_coord(p.x, sizes.x), table_coord(p.y, sizes.x), w);
    samples[id.x] = textureSampleLevel(table, table_sampler, uvw, 0.0);
}
"#;

fn storage(gpu: &Gpu, data: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    wgpu::util::DeviceExt::create_buffer_init(
        &gpu.device,
        &wgpu::util::BufferInitDescriptor {
            label: None,
            contents: data,
            usage: wgpu::BufferUsages::STORAGE | usage,
        },
    )
}

/// Samples `data` (`size` texels, x fastest) at `points` on the GPU.
fn gpu_samples(gpu: &Gpu, size: [u32; 3], data: &[[f32; 4]], points: &[[f32; 4]]) -> Vec<[f32; 4]> {
    let mut ledger = MemoryLedger::default();
    let table = TableTexture::new(gpu, &mut ledger, "test table", size, data).unwrap();
    assert!(table.filterable, "lavapipe filters Rgba32Float");
    let none = wgpu::BufferUsages::empty();
    let points_buf = storage(gpu, bytemuck::cast_slice(points), none);
    let out = storage(
        gpu,
        &vec![0u8; points.len() * 16],
        wgpu::BufferUsages::COPY_SRC,
    );
    let sizes = [size[0] as f32, size[2] as f32, 0.0, 0.0];
    let sizes_buf = storage(gpu, bytemuck::cast_slice(&sizes), none);
    let compute = wgpu::ShaderStages::COMPUTE;
    let mut entries = TableTexture::layout_entries(true, 0, 1, compute).to_vec();
    entries.push(render_core::bind::storage_entry(2, compute, true));
    entries.push(render_core::bind::storage_entry(3, compute, false));
    entries.push(render_core::bind::storage_entry(4, compute, true));
    let layout = gpu
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: None,
            entries: &entries,
        });
    let module = gpu.shader("table sampler", &format!("{TABLE_WGSL}\n{SAMPLER}"));
    let pipeline_layout =
        render_core::bind::pipeline_layout(gpu, "table sampler", &[Some(&layout)]);
    let pipeline = gpu.compute_pipeline("table sampler", Some(&pipeline_layout), &module, "main");
    let mut bind_entries = table.bind_entries(0, 1).to_vec();
    bind_entries.push(render_core::bind::whole(2, &points_buf));
    bind_entries.push(render_core::bind::whole(3, &out));
    bind_entries.push(render_core::bind::whole(4, &sizes_buf));
    let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &bind_entries,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((points.len() as u32).div_ceil(64), 1, 1);
    }
    gpu.queue.submit([enc.finish()]);
    let bytes = gpu.read_buffer(&out, 0, points.len() as u64 * 16).unwrap();
    bytemuck::cast_slice(&bytes).to_vec()
}

/// The largest difference a filtered sample may show against the CPU's interpolation: f32
/// rounding, plus an interpolation weight rounded to 1/256 on each of three axes (what GPUs'
/// samplers do; lavapipe's weights are f32), each moving the sample by at most 1/512 of the
/// largest difference of two entries. A coordinate off by half a texel, or axes swapped, moves
/// a sample of these random entries by a quarter of that difference on average.
fn tolerance(data: &[[f32; 4]]) -> f64 {
    let (lo, hi) = data
        .iter()
        .flatten()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &v| {
            (lo.min(v as f64), hi.max(v as f64))
        });
    1e-5 + 3.0 * (hi - lo) / 512.0
}

fn random_entries(rng: &mut Rng, n: usize) -> Vec<[f32; 4]> {
    (0..n)
        .map(|_| std::array::from_fn(|_| rng.unit() as f32))
        .collect()
}

fn assert_close(p: &[f32; 4], got: &[f32; 4], want: [f64; 4], tol: f64) {
    for c in 0..4 {
        assert!(
            (got[c] as f64 - want[c]).abs() <= tol,
            "at {p:?} channel {c}: GPU {} against CPU {} (tolerance {tol:.2e})",
            got[c],
            want[c]
        );
    }
}

#[test]
fn a_filtered_3d_sample_is_the_cpu_tables_trilinear_sample() {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let (n_s, n_l) = (9usize, 5usize);
    let table = Table3d {
        n_s,
        n_l,
        max_length_world: 2.0,
        length_unit: 1.0,
        data: random_entries(&mut rng, n_s * n_s * n_l),
    };
    // Interior points, the ends of every axis, and lengths past the longest (clamped).
    let mut points: Vec<[f32; 4]> = (0..1000)
        .map(|_| {
            [
                rng.unit() as f32,
                rng.unit() as f32,
                (rng.unit() * 1.2) as f32,
                0.0,
            ]
        })
        .collect();
    points.extend([[0.0; 4], [1.0, 1.0, 1.0, 0.0], [0.0, 1.0, 0.5, 0.0]]);
    let size = [n_s as u32, n_s as u32, n_l as u32];
    let got = gpu_samples(&gpu, size, &table.data, &points);
    let tol = tolerance(&table.data);
    for (p, g) in points.iter().zip(&got) {
        let want = table.sample(p[0] as f64, p[1] as f64, p[2] as f64 * 2.0);
        assert_close(p, g, want, tol);
    }
}

#[test]
fn a_2d_table_is_one_layer_of_the_texture() {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let n_s = 17usize;
    let table = Table2d {
        n_s,
        length_world: 1.0,
        length_unit: 1.0,
        data: random_entries(&mut rng, n_s * n_s),
    };
    let points: Vec<[f32; 4]> = (0..1000)
        .map(|_| [rng.unit() as f32, rng.unit() as f32, 0.0, 0.0])
        .collect();
    let got = gpu_samples(&gpu, [n_s as u32, n_s as u32, 1], &table.data, &points);
    let tol = tolerance(&table.data);
    for (p, g) in points.iter().zip(&got) {
        assert_close(p, g, table.sample(p[0] as f64, p[1] as f64), tol);
    }
}
