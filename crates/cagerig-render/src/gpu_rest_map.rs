//! The display path's rest skin on the GPU: a [`DisplayRestMapBackend`] ("wgpu") that a front end
//! passes in `SessionOptions::display_rest_map` as `DisplayRestMap::External`.
//!
//! On the f32 display path a current-cage edit draws the rest skin as one product of the whole
//! coordinate matrix with the cage, M̃ = K̃·[C; g] (`#V × #K`, `#K` = `#C` for mean value rigs,
//! `#C + #F` for Green rigs, whose face terms g are extra columns). [`GpuRestMap::bind`] copies
//! the coordinates once per binding into a storage buffer in f32, and every
//! [`DisplayRestMapProduct::apply`] uploads the `#K` points, runs one compute pass (one
//! invocation per skin vertex, summing over the columns in f32) and reads M̃ back into the
//! session's buffer. The sync operators never read M̃, so this backend changes what is drawn and
//! nothing else.
//!
//! # Layout
//!
//! The coefficient matrix K̃ has `#K + 1` columns: `0..#C` the vertex part (Φ or φ), `#C..#K`
//! the kind's extra columns (ψ), and last the row sums s_i = Σ_{k<#C} Φ[i, k] (summed in f64,
//! then rounded), padded with zero columns to B = ⌈(#K + 1)/4⌉ blocks of four. The storage
//! buffer holds it as B column blocks of `#V` vec4s (`#V × 4B` f32, `16·#V·B` bytes): block b
//! occupies vec4s `[b·#V, (b + 1)·#V)`, and vec4 `b·#V + i` holds row i's coefficients of
//! columns 4b … 4b + 3. At each step of the shader's loop over the blocks, neighbouring
//! invocations (neighbouring skin vertices) read neighbouring 16-byte words, which the memory
//! system serves as whole lines (one 4-byte column per step took about twice as long on
//! lavapipe).
//!
//! The 4B points the columns multiply go to a uniform buffer (the same index for every
//! invocation), in world space but moved to an origin o near the cage: `C_k − o` for the vertex
//! columns (o is the midpoint of the rest cage's bounding box, chosen per event), the terms `g_f`
//! unchanged (they do not translate), o for the row-sum column, and zero for the padding. Since
//! Σ_k Φ[i, k]·C_k = Σ_k Φ[i, k]·(C_k − o) + s_i·o exactly, the product is M̃ for any
//! coordinates, and the f32 sums scale with the cage's size instead of its distance from the
//! world origin. The uniform array holds 1024 points: a rig with more than 1023 columns is
//! refused ([`GpuRestMapError::TooManyColumns`]).
//!
//! # Error
//!
//! Each coefficient and each point is rounded once to f32 (relative error u = 2⁻²⁴ each) and the
//! terms are summed in f32 (four per block, then into the running sum; with or without fused
//! multiply-adds). Per coordinate axis, to first order in u,
//!
//! |M̃_i − M_i| ≤ (#K + 4)·u·(Σ_{k<#K} |K̃[i, k]|·|P_k| + |s_i|·|o|),
//!
//! with P_k the moved points above (no term goes through more than #K + 2 roundings; the last
//! u covers the second-order terms). Worst cases need every rounding to go the same way:
//! measured on the Arm the drawn M̃ is within 1.5–2.7e-7 of the diagonal of the exact M (the
//! CPU backend's: 1.0–1.6e-7), inside the display path's 2e-6. The unit tests check the bound per
//! vertex on coordinates with negative entries far from the origin; `tests/gpu_rest_map.rs`
//! checks the 2e-6 on the bound Arm.
//!
//! # Failure
//!
//! [`DisplayRestMapProduct::apply`] cannot return an error. The product keeps a host copy of its
//! f32 coefficients (the same `#V × 4B` floats, about as much host memory as the CPU backend's
//! Φ̃) and, if the GPU fails to deliver a result (device lost, mapping refused), computes that
//! event and every later one on the CPU from that copy (summed in f64, within the same bound),
//! so the drawn skin is always the stated product. [`GpuRestMap::counts`] and
//! [`GpuRestMap::first_failure`] tell a front end that this happened. `apply` with lengths that
//! do not match the bound coordinates leaves `out` untouched (the session never calls it so).

use std::fmt;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use cagerig::cage_coords::CageCoords;
use cagerig::session::{DisplayRestMapBackend, DisplayRestMapProduct};
use glam::{DVec3, Vec3};
use rayon::iter::{IndexedParallelIterator, ParallelIterator};
use rayon::slice::ParallelSliceMut;
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::gpu::GpuContext;

/// Invocations per workgroup (`@workgroup_size` of `shaders/rest_map.wgsl`).
const WORKGROUP_SIZE: u32 = 64;

/// Rows per tile of the CPU fallback's product (f64 sums of a tile stay in L1).
const CPU_TILE: usize = 256;

/// Points of the uniform buffer (`array<vec4<f32>, 1024>` in the shader, the 16 KiB every
/// device allows): at most 1023 coordinate columns and the row-sum column.
const MAX_POINTS: usize = 1024;

/// Why [`GpuRestMap`] could not be opened, or could not hold a binding's coordinates.
#[derive(Debug, thiserror::Error)]
pub enum GpuRestMapError {
    /// No adapter or device ([`GpuContext::new_headless`]).
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The device cannot run this compute shader (e.g. a GLES 3.0 / WebGL2 adapter).
    #[error("the graphics device cannot run the rest-map compute shader: {0}")]
    NoCompute(String),
    /// One buffer would exceed the device's storage-buffer or buffer-size limit (or the cap of
    /// [`GpuRestMap::with_max_bytes`]).
    #[error("the rest map needs {bytes} bytes in one GPU buffer; the limit is {limit}")]
    TooLarge {
        /// Bytes of the largest buffer.
        bytes: u64,
        /// The device's limit (or the cap).
        limit: u64,
    },
    /// More coordinate columns than the shader's uniform array of points holds.
    #[error("the rest map takes at most {max} coordinate columns, not {columns}")]
    TooManyColumns {
        /// `#K`.
        columns: usize,
        /// The most the shader holds.
        max: usize,
    },
    /// The coordinate parts are empty or their row counts differ.
    #[error("the rest map's coordinates are not one #V × #K matrix: {0}")]
    Shape(String),
    /// The GPU reported an error (out of memory, validation).
    #[error("the GPU reported an error: {0}")]
    Gpu(String),
}

/// What a [`GpuRestMap`] and its products have done so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GpuRestMapCounts {
    /// Bindings whose coordinates the GPU holds.
    pub bound: u64,
    /// Bindings refused ([`GpuRestMap::last_refusal`] says why); the session then computes the
    /// exact M in full.
    pub refused: u64,
    /// Products M̃ computed on the GPU.
    pub gpu_applies: u64,
    /// Products M̃ computed on the CPU after the GPU failed ([`GpuRestMap::first_failure`]).
    pub cpu_applies: u64,
}

/// Counters shared by a backend and its products.
#[derive(Debug, Default)]
struct Counters {
    bound: AtomicU64,
    refused: AtomicU64,
    gpu_applies: AtomicU64,
    cpu_applies: AtomicU64,
    last_refusal: Mutex<Option<String>>,
    first_failure: OnceLock<String>,
}

/// The wgpu backend of the display path's rest skin (name "wgpu"): holds a device, its queue and
/// the compute pipeline; each binding gets a [`GpuRestMapProduct`].
pub struct GpuRestMap {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter_name: String,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    max_bytes: u64,
    counters: Arc<Counters>,
}

impl fmt::Debug for GpuRestMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("GpuRestMap")
            .field("adapter", &self.adapter_name)
            .field("max_bytes", &self.max_bytes)
            .field("counts", &self.counts())
            .finish()
    }
}

impl GpuRestMap {
    /// The backend on `gpu`'s device (shared with a renderer on the same context: the device and
    /// queue are reference-counted handles). Fails with [`GpuRestMapError::NoCompute`] when the
    /// device lacks compute shaders or three storage buffers per stage.
    pub fn new(gpu: &GpuContext) -> Result<Self, GpuRestMapError> {
        let device = gpu.device.clone();
        let limits = device.limits();
        if limits.max_storage_buffers_per_shader_stage < 3
            || limits.max_compute_invocations_per_workgroup < WORKGROUP_SIZE
            || limits.max_compute_workgroup_size_x < WORKGROUP_SIZE
            || limits.max_compute_workgroups_per_dimension == 0
        {
            return Err(GpuRestMapError::NoCompute(format!(
                "{}: {} storage buffers per stage, {} invocations per workgroup",
                gpu.adapter_name,
                limits.max_storage_buffers_per_shader_stage,
                limits.max_compute_invocations_per_workgroup
            )));
        }
        let scopes = ErrorScopes::push(&device);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("rest map"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/rest_map.wgsl").into()),
        });
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("rest map"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage(1, true),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage(3, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("rest map"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("rest map"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            cache: None,
        });
        scopes.pop().map_err(GpuRestMapError::Gpu)?;
        Ok(Self {
            queue: gpu.queue.clone(),
            adapter_name: gpu.adapter_name.clone(),
            layout,
            pipeline,
            max_bytes: limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size),
            counters: Arc::default(),
            device,
        })
    }

    /// The backend on a headless device of its own ([`GpuContext::new_headless`]).
    pub fn new_headless() -> Result<Self, GpuRestMapError> {
        Self::new(&GpuContext::new_headless()?)
    }

    /// Caps each buffer at `bytes` (below the device's own limits), e.g. to leave the GPU's
    /// memory to the renderer: a binding whose coefficients need more is refused, and the
    /// session computes the exact M in full.
    #[must_use]
    pub fn with_max_bytes(mut self, bytes: u64) -> Self {
        self.max_bytes = self.max_bytes.min(bytes);
        self
    }

    /// Name and backend of the adapter.
    pub fn adapter_name(&self) -> &str {
        &self.adapter_name
    }

    /// The largest buffer a binding may use, in bytes (the coefficients take `16·#V·⌈(#K + 1)/4⌉`).
    pub fn max_bytes(&self) -> u64 {
        self.max_bytes
    }

    /// What this backend and its products have done so far.
    pub fn counts(&self) -> GpuRestMapCounts {
        let c = &self.counters;
        GpuRestMapCounts {
            bound: c.bound.load(Ordering::Relaxed),
            refused: c.refused.load(Ordering::Relaxed),
            gpu_applies: c.gpu_applies.load(Ordering::Relaxed),
            cpu_applies: c.cpu_applies.load(Ordering::Relaxed),
        }
    }

    /// Why the last refused binding was refused.
    pub fn last_refusal(&self) -> Option<String> {
        self.counters
            .last_refusal
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// The first GPU failure of a product (after which it computes on the CPU).
    pub fn first_failure(&self) -> Option<&str> {
        self.counters.first_failure.get().map(String::as_str)
    }

    /// Copies the columns of `parts` side by side (`#V × #K`: the vertex part first, each part
    /// `#V` rows) to the GPU in f32, with the row sums of the first part as one more column (see
    /// the module notes). Fails when the parts' row counts differ, a buffer would exceed
    /// [`Self::max_bytes`] or the dispatch limits, or there are more than 1023 columns.
    pub fn bind(&self, parts: &[&CageCoords]) -> Result<GpuRestMapProduct, GpuRestMapError> {
        let Some(first) = parts.first() else {
            return Err(GpuRestMapError::Shape("no coordinate parts".into()));
        };
        let nv = first.num_vertices();
        if nv == 0 {
            return Err(GpuRestMapError::Shape("no skin vertices".into()));
        }
        if let Some(part) = parts.iter().find(|p| p.num_vertices() != nv) {
            return Err(GpuRestMapError::Shape(format!(
                "parts of {nv} and {} rows",
                part.num_vertices()
            )));
        }
        let head_columns = first.num_cage_vertices();
        let data_columns: usize = parts.iter().map(|p| p.num_cage_vertices()).sum();
        let blocks = (data_columns + 1).div_ceil(4);
        if 4 * blocks > MAX_POINTS {
            return Err(GpuRestMapError::TooManyColumns {
                columns: data_columns,
                max: MAX_POINTS - 1,
            });
        }
        let words = nv
            .checked_mul(4 * blocks)
            .filter(|&w| w / 4 <= u32::MAX as usize);
        let too_large = |bytes: u64| GpuRestMapError::TooLarge {
            bytes,
            limit: self.max_bytes,
        };
        let Some(words) = words else {
            return Err(too_large(u64::MAX));
        };
        let coeff_bytes = words as u64 * 4;
        let skin_bytes = nv as u64 * 12;
        let largest = coeff_bytes.max(skin_bytes);
        if largest > self.max_bytes {
            return Err(too_large(largest));
        }
        let workgroups = dispatch_size(
            nv,
            self.device.limits().max_compute_workgroups_per_dimension,
        )
        .ok_or_else(|| {
            GpuRestMapError::NoCompute(format!("{nv} vertices exceed the dispatch limits"))
        })?;

        let mut host = Vec::new();
        host.try_reserve_exact(words / 4)
            .map_err(|e| GpuRestMapError::Gpu(format!("host copy of the coefficients: {e}")))?;
        host.resize(words / 4, [0.0f32; 4]);
        let mut sums = vec![0.0f64; nv];
        for k in 0..head_columns {
            for (s, &w) in sums.iter_mut().zip(first.column(k)) {
                *s += w;
            }
        }
        let columns = parts
            .iter()
            .flat_map(|part| (0..part.num_cage_vertices()).map(move |k| part.column(k)))
            .chain([&sums[..]]);
        for (k, column) in columns.enumerate() {
            let block = &mut host[(k / 4) * nv..(k / 4 + 1) * nv];
            for (slot, &w) in block.iter_mut().zip(column) {
                slot[k % 4] = w as f32;
            }
        }
        drop(sums);

        let device = &self.device;
        let scopes = ErrorScopes::push(device);
        let coefficients = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("rest map coefficients"),
            contents: bytemuck::cast_slice(&host),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let params = [
            nv as u32,
            blocks as u32,
            workgroups[0] * WORKGROUP_SIZE,
            0u32,
        ];
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("rest map shape"),
            contents: bytemuck::cast_slice(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let points = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rest map points"),
            size: (MAX_POINTS * 16) as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let skin = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rest map skin"),
            size: skin_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rest map readback"),
            size: skin_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("rest map"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: coefficients.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: points.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: skin.as_entire_binding(),
                },
            ],
        });
        scopes.pop().map_err(GpuRestMapError::Gpu)?;
        Ok(GpuRestMapProduct {
            device: self.device.clone(),
            queue: self.queue.clone(),
            pipeline: self.pipeline.clone(),
            bind_group,
            points,
            skin,
            readback,
            skin_bytes,
            workgroups,
            num_vertices: nv,
            head_columns,
            data_columns,
            host,
            staging: Mutex::new(vec![[0.0; 4]; 4 * blocks]),
            map_state: Arc::new(AtomicU8::new(MAP_IDLE)),
            failed: AtomicBool::new(false),
            counters: Arc::clone(&self.counters),
        })
    }
}

impl DisplayRestMapBackend for GpuRestMap {
    fn name(&self) -> &str {
        "wgpu"
    }

    fn upload(&self, parts: &[&CageCoords]) -> Option<Arc<dyn DisplayRestMapProduct>> {
        match self.bind(parts) {
            Ok(product) => {
                self.counters.bound.fetch_add(1, Ordering::Relaxed);
                Some(Arc::new(product))
            }
            Err(e) => {
                self.counters.refused.fetch_add(1, Ordering::Relaxed);
                *self
                    .counters
                    .last_refusal
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner) = Some(e.to_string());
                None
            }
        }
    }
}

/// Workgroups `[x, y]` covering `nv` invocations with at most `max_per_dimension` per axis.
fn dispatch_size(nv: usize, max_per_dimension: u32) -> Option<[u32; 2]> {
    let groups = u32::try_from(nv.div_ceil(WORKGROUP_SIZE as usize)).ok()?;
    let x = groups.min(max_per_dimension);
    if x == 0 {
        return None;
    }
    let y = groups.div_ceil(x);
    (y <= max_per_dimension).then_some([x, y])
}

/// Validation and out-of-memory error scopes around buffer and pipeline creation, so that a
/// failure is an error instead of wgpu's default handler (which panics).
struct ErrorScopes {
    validation: wgpu::ErrorScopeGuard,
    memory: wgpu::ErrorScopeGuard,
}

impl ErrorScopes {
    fn push(device: &wgpu::Device) -> Self {
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        Self { validation, memory }
    }

    fn pop(self) -> Result<(), String> {
        let memory = pollster::block_on(self.memory.pop());
        let validation = pollster::block_on(self.validation.pop());
        match memory.or(validation) {
            Some(e) => Err(e.to_string()),
            None => Ok(()),
        }
    }
}

const MAP_IDLE: u8 = 0;
const MAP_PENDING: u8 = 1;
const MAP_DONE: u8 = 2;
const MAP_FAILED: u8 = 3;

/// One binding's coefficients on the GPU (see the module notes for the layout): `#V × 4B` f32
/// in B column blocks of four, plus the per-event buffers (points, skin, readback) and a host copy for the
/// CPU fallback.
pub struct GpuRestMapProduct {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// 4B points (xyz, w unused), written per event (a uniform buffer of 1024 points).
    points: wgpu::Buffer,
    /// M̃, `3·#V` f32, written by the shader.
    skin: wgpu::Buffer,
    /// M̃ copied for mapping.
    readback: wgpu::Buffer,
    skin_bytes: u64,
    workgroups: [u32; 2],
    num_vertices: usize,
    /// `#C`: the columns of the vertex part, moved to the origin o.
    head_columns: usize,
    /// `#K`: every coordinate column, without the row-sum column.
    data_columns: usize,
    /// The coefficients as uploaded (B blocks of `#V` rows of four columns), for the CPU
    /// fallback.
    host: Vec<[f32; 4]>,
    /// The event's 4B points (reused; the lock also serialises the use of `readback`).
    staging: Mutex<Vec<[f32; 4]>>,
    /// The readback buffer's mapping, set by wgpu's callback.
    map_state: Arc<AtomicU8>,
    /// Whether the GPU failed once (every later product is computed on the CPU).
    failed: AtomicBool,
    counters: Arc<Counters>,
}

impl fmt::Debug for GpuRestMapProduct {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("GpuRestMapProduct")
            .field("num_vertices", &self.num_vertices)
            .field("columns", &self.data_columns)
            .field("failed", &self.failed.load(Ordering::Relaxed))
            .finish_non_exhaustive()
    }
}

impl GpuRestMapProduct {
    /// Number of skin vertices `#V`.
    pub fn num_vertices(&self) -> usize {
        self.num_vertices
    }

    /// Number of coordinate columns `#K` (`#C`, plus `#F` for Green rigs).
    pub fn num_columns(&self) -> usize {
        self.data_columns
    }

    /// Whether the GPU failed and the product now runs on the CPU.
    pub fn has_failed(&self) -> bool {
        self.failed.load(Ordering::Relaxed)
    }

    /// M̃ = K̃·[`head`; `tail`] from the host copy of the f32 coefficients, summed in f64 on the
    /// CPU (what [`DisplayRestMapProduct::apply`] falls back to). Leaves `out` untouched when
    /// the lengths do not match (`head` `#C`, `tail` `#K − #C`, `out` `#V`).
    pub fn apply_on_cpu(&self, head: &[DVec3], tail: &[DVec3], out: &mut [Vec3]) {
        if !self.lengths_match(head, tail, out) {
            return;
        }
        let mut points = self.staging.lock().unwrap_or_else(PoisonError::into_inner);
        fill_points(head, tail, &mut points);
        self.product_on_cpu(&points, out);
    }

    fn lengths_match(&self, head: &[DVec3], tail: &[DVec3], out: &[Vec3]) -> bool {
        head.len() == self.head_columns
            && head.len() + tail.len() == self.data_columns
            && out.len() == self.num_vertices
    }

    /// One compute pass and the readback of M̃ into `out`.
    fn product_on_gpu(&self, points: &[[f32; 4]], out: &mut [Vec3]) -> Result<(), String> {
        self.queue
            .write_buffer(&self.points, 0, bytemuck::cast_slice(points));
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("rest map"),
            });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("rest map"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.dispatch_workgroups(self.workgroups[0], self.workgroups[1], 1);
        }
        encoder.copy_buffer_to_buffer(&self.skin, 0, &self.readback, 0, Some(self.skin_bytes));
        let submission = self.queue.submit([encoder.finish()]);
        self.map_state.store(MAP_PENDING, Ordering::Release);
        let state = Arc::clone(&self.map_state);
        self.readback
            .map_async(wgpu::MapMode::Read, .., move |result| {
                let done = if result.is_ok() { MAP_DONE } else { MAP_FAILED };
                state.store(done, Ordering::Release);
            });
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(submission),
                timeout: None,
            })
            .map_err(|e| e.to_string())?;
        if self.map_state.load(Ordering::Acquire) == MAP_PENDING {
            self.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| e.to_string())?;
        }
        match self.map_state.load(Ordering::Acquire) {
            MAP_DONE => {}
            MAP_FAILED => return Err("mapping M̃ for reading failed".into()),
            _ => return Err("M̃ was not mapped after the wait".into()),
        }
        {
            let view = self
                .readback
                .get_mapped_range(..)
                .map_err(|e| e.to_string())?;
            for (o, xyz) in out.iter_mut().zip(view.chunks_exact(12)) {
                *o = Vec3::from_array(bytemuck::pod_read_unaligned::<[f32; 3]>(xyz));
            }
        }
        self.readback.unmap();
        self.map_state.store(MAP_IDLE, Ordering::Release);
        Ok(())
    }

    /// M̃ from the host copy, f64 sums over tiles of [`CPU_TILE`] rows, in parallel.
    fn product_on_cpu(&self, points: &[[f32; 4]], out: &mut [Vec3]) {
        let nv = self.num_vertices;
        out.par_chunks_mut(CPU_TILE)
            .enumerate()
            .for_each(|(tile, out)| {
                let first = tile * CPU_TILE;
                let mut sums = [DVec3::ZERO; CPU_TILE];
                for (b, p) in points.chunks_exact(4).enumerate() {
                    let p: [DVec3; 4] = std::array::from_fn(|j| {
                        p.get(j)
                            .map_or(DVec3::ZERO, |p| Vec3::from_slice(&p[..3]).as_dvec3())
                    });
                    let start = b * nv + first;
                    let Some(block) = self.host.get(start..start + out.len()) else {
                        return;
                    };
                    for (s, w) in sums.iter_mut().zip(block) {
                        *s += f64::from(w[0]) * p[0]
                            + f64::from(w[1]) * p[1]
                            + f64::from(w[2]) * p[2]
                            + f64::from(w[3]) * p[3];
                    }
                }
                for (o, s) in out.iter_mut().zip(&sums) {
                    *o = s.as_vec3();
                }
            });
    }
}

/// The points of one event (see the module notes): `C_k − o` for the vertex columns, the terms
/// `g_f`, then o, the midpoint of the bounding box of `head`; each rounded to f32.
fn fill_points(head: &[DVec3], tail: &[DVec3], points: &mut [[f32; 4]]) {
    let origin = if head.is_empty() {
        DVec3::ZERO
    } else {
        let lo = head.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
        let hi = head.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
        0.5 * (lo + hi)
    };
    let moved = head.iter().map(|&c| c - origin);
    let mut slots = points.iter_mut();
    for (slot, p) in (&mut slots).zip(moved.chain(tail.iter().copied()).chain([origin])) {
        let p = p.as_vec3();
        *slot = [p.x, p.y, p.z, 0.0];
    }
    // The padding columns are zero; so are their points.
    slots.for_each(|slot| *slot = [0.0; 4]);
}

impl DisplayRestMapProduct for GpuRestMapProduct {
    /// M̃ = K̃·[`head`; `tail`] into `out` (`#V`, f32) on the GPU, within the module's stated
    /// bound; on the CPU from the host copy once the GPU has failed (see the module notes).
    /// Leaves `out` untouched when the lengths do not match the bound coordinates.
    fn apply(&self, head: &[DVec3], tail: &[DVec3], out: &mut [Vec3]) {
        if !self.lengths_match(head, tail, out) {
            return;
        }
        let mut points = self.staging.lock().unwrap_or_else(PoisonError::into_inner);
        fill_points(head, tail, &mut points);
        if !self.failed.load(Ordering::Relaxed) {
            match self.product_on_gpu(&points, out) {
                Ok(()) => {
                    self.counters.gpu_applies.fetch_add(1, Ordering::Relaxed);
                    return;
                }
                Err(reason) => {
                    self.failed.store(true, Ordering::Relaxed);
                    let _ = self.counters.first_failure.set(reason);
                }
            }
        }
        self.product_on_cpu(&points, out);
        self.counters.cpu_applies.fetch_add(1, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cagerig::session::DyadicProductCheck;

    /// The backend on a headless device, or `None` where `CAGERIG_SKIP_GPU_TESTS` is set. With no
    /// adapter and no such variable the test fails, as the renderer's tests do: a GPU test does not
    /// pass by not running.
    fn backend() -> Option<GpuRestMap> {
        if std::env::var_os("CAGERIG_SKIP_GPU_TESTS").is_some() {
            eprintln!("skipped: CAGERIG_SKIP_GPU_TESTS is set");
            return None;
        }
        match GpuRestMap::new_headless() {
            Ok(backend) => Some(backend),
            Err(e) => panic!("{e} (set CAGERIG_SKIP_GPU_TESTS=1 to skip the GPU tests)"),
        }
    }

    #[test]
    fn dyadic_coordinates_give_the_exact_product() {
        let Some(gpu) = backend() else { return };
        let coords = DyadicProductCheck::coords();
        let product = gpu.upload(&[&coords, &coords]).unwrap();
        assert_eq!(
            DyadicProductCheck::apply(&*product),
            DyadicProductCheck::EXPECTED
        );
        assert_eq!(gpu.name(), "wgpu");
        let counts = gpu.counts();
        assert_eq!(
            (counts.bound, counts.gpu_applies, counts.cpu_applies),
            (1, 1, 0)
        );
    }

    /// `#V` rows over `nc` vertex columns (a partition of unity with negative entries, like mean
    /// value coordinates) and `nf` extra columns of either sign.
    fn coordinates(nv: usize, nc: usize, nf: usize) -> (CageCoords, CageCoords) {
        let entry = |i: usize, k: usize| ((i * 37 + k * 11) % 97) as f64 / 97.0 - 0.2;
        let rows: Vec<Vec<f64>> = (0..nv)
            .map(|i| {
                let mut row: Vec<f64> = (0..nc - 1).map(|k| entry(i, k) / nc as f64).collect();
                row.push(1.0 - row.iter().sum::<f64>());
                row
            })
            .collect();
        let extra: Vec<Vec<f64>> = (0..nv)
            .map(|i| (0..nf).map(|f| entry(i, f + 50) * 0.3).collect())
            .collect();
        (
            CageCoords::from_rows(&rows, nc).unwrap(),
            CageCoords::from_rows(&extra, nf).unwrap(),
        )
    }

    #[test]
    fn the_product_is_within_the_stated_bound_far_from_the_origin() {
        let Some(gpu) = backend() else { return };
        let (nv, nc, nf) = (5000, 9, 5);
        let (phi, psi) = coordinates(nv, nc, nf);
        // A cage of size ≈ 2 about (1000, −500, 250): centring keeps the f32 sums at its scale.
        let centre = DVec3::new(1000.0, -500.0, 250.0);
        let head: Vec<DVec3> = (0..nc)
            .map(|k| {
                let t = k as f64;
                centre + DVec3::new(t.sin(), (1.3 * t).cos(), 0.7 * t.sin() * t.cos())
            })
            .collect();
        let tail: Vec<DVec3> = (0..nf)
            .map(|f| DVec3::new(0.1 * f as f64, -0.05, 0.02 * f as f64))
            .collect();
        let product = gpu.bind(&[&phi, &psi]).unwrap();
        assert_eq!(
            (product.num_vertices(), product.num_columns()),
            (nv, nc + nf)
        );
        let mut on_gpu = vec![Vec3::ZERO; nv];
        let mut on_cpu = vec![Vec3::ZERO; nv];
        product.apply(&head, &tail, &mut on_gpu);
        product.apply_on_cpu(&head, &tail, &mut on_cpu);
        assert!(!product.has_failed());
        let lo = head.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
        let hi = head.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
        let origin = 0.5 * (lo + hi);
        let u = f64::from(f32::EPSILON) / 2.0; // 2⁻²⁴, the f32 unit round-off
        let factor = (nc + nf + 4) as f64 * u;
        let mut worst = 0.0f64;
        for i in 0..nv {
            let mut exact = DVec3::ZERO;
            let mut magnitude = DVec3::ZERO;
            let mut row_sum = 0.0;
            for (k, &c) in head.iter().enumerate() {
                let w = phi.get(i, k);
                exact += w * c;
                magnitude += w.abs() * (c - origin).abs();
                row_sum += w;
            }
            for (f, &g) in tail.iter().enumerate() {
                let w = psi.get(i, f);
                exact += w * g;
                magnitude += w.abs() * g.abs();
            }
            let bound = factor * (magnitude + row_sum.abs() * origin.abs());
            for shown in [on_gpu[i], on_cpu[i]] {
                let error = (shown.as_dvec3() - exact).abs();
                assert!(
                    error.cmple(bound).all(),
                    "vertex {i}: {shown} against {exact}, error {error} > {bound}"
                );
                worst = worst.max((error / bound).max_element());
            }
        }
        assert!(worst <= 1.0, "{worst}");
    }

    #[test]
    fn a_binding_over_the_cap_is_refused() {
        let Some(gpu) = backend() else { return };
        let gpu = gpu.with_max_bytes(16);
        assert_eq!(gpu.max_bytes(), 16);
        let phi = DyadicProductCheck::coords();
        assert!(gpu.upload(&[&phi]).is_none());
        let counts = gpu.counts();
        assert_eq!((counts.bound, counts.refused), (0, 1));
        let reason = gpu.last_refusal().unwrap();
        assert!(reason.contains("bytes"), "{reason}");
        assert!(matches!(
            gpu.bind(&[&phi]),
            Err(GpuRestMapError::TooLarge { limit: 16, .. })
        ));
    }

    #[test]
    fn parts_of_different_heights_or_none_are_refused() {
        let Some(gpu) = backend() else { return };
        let (phi, _) = coordinates(4, 3, 1);
        let short = DyadicProductCheck::coords();
        assert!(matches!(
            gpu.bind(&[&phi, &short]),
            Err(GpuRestMapError::Shape(_))
        ));
        assert!(matches!(gpu.bind(&[]), Err(GpuRestMapError::Shape(_))));
    }

    #[test]
    fn more_columns_than_the_uniform_array_holds_are_refused() {
        let Some(gpu) = backend() else { return };
        let row = vec![1.0 / 1024.0; 1024];
        let phi = CageCoords::from_rows(&[row], 1024).unwrap();
        assert!(matches!(
            gpu.bind(&[&phi]),
            Err(GpuRestMapError::TooManyColumns {
                columns: 1024,
                max: 1023
            })
        ));
    }

    #[test]
    fn lengths_that_do_not_match_leave_the_output_untouched() {
        let Some(gpu) = backend() else { return };
        let product = gpu.upload(&[&DyadicProductCheck::coords()]).unwrap();
        let mut out = [Vec3::splat(7.0); 3];
        product.apply(&[DVec3::ONE], &[], &mut out);
        product.apply(&[DVec3::ONE, DVec3::ONE], &[DVec3::ONE], &mut out);
        product.apply(&[DVec3::ONE, DVec3::ONE], &[], &mut out[..2]);
        assert_eq!(out, [Vec3::splat(7.0); 3]);
        assert_eq!(gpu.counts().gpu_applies, 0);
    }

    #[test]
    fn the_dispatch_covers_every_vertex_within_the_limits() {
        assert_eq!(dispatch_size(1, 65_535), Some([1, 1]));
        assert_eq!(dispatch_size(64, 65_535), Some([1, 1]));
        assert_eq!(dispatch_size(65, 65_535), Some([2, 1]));
        assert_eq!(dispatch_size(64 * 65_536, 65_535), Some([65_535, 2]));
        assert_eq!(dispatch_size(1000, 0), None);
        assert_eq!(dispatch_size(64 * 10 + 1, 3), None);
        let [x, y] = dispatch_size(133_073, 65_535).unwrap();
        assert!((x * y * WORKGROUP_SIZE) as usize >= 133_073);
    }
}
