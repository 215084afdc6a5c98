//! The GPU copy of one view's [`Scene`]: vertex, index and instance buffers updated in place
//! each frame (buffers are re-created only when a layer grows), with normals recomputed from the
//! current positions.

use glam::DVec3;
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::gpu_buffer::GrowBuffer;
use crate::gpu_types::{LineInstance, MaterialUniform, MeshVertex, PointInstance};
use crate::pipelines::Pipelines;
use crate::scene::{Bounds, EMPTY_BOUNDS, MeshPositions, Scene, Style, unique_edges};
use crate::vertex_normals::VertexNormals;
use crate::vertex_packing::VertexSource;

/// Vertex data from this size up is written through the staging belt.
const STAGED_BYTES: usize = 256 * 1024;

/// A shaded triangle layer (the skin or the cage faces).
struct SurfaceBuffers {
    vertices: GrowBuffer,
    indices: GrowBuffer,
    material: wgpu::Buffer,
    material_bind: wgpu::BindGroup,
    /// Triangles last uploaded (the index buffer is rewritten only when they change).
    triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    /// The vertex count `triangles` were checked against.
    checked_vertices: usize,
    /// The caller's id of `triangles` (see `MeshLayer::topology_id`).
    topology_id: Option<u64>,
    vertex_normals: VertexNormals,
    /// Staging chunks of the vertex uploads, reused between frames.
    belt: wgpu::util::StagingBelt,
    packed: Vec<MeshVertex>,
    visible: bool,
}

impl SurfaceBuffers {
    fn new(device: &wgpu::Device, pipelines: &Pipelines, label: &'static str) -> Self {
        let material = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(&MaterialUniform::default()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let material_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &pipelines.material_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: material.as_entire_binding(),
            }],
        });
        Self {
            vertices: GrowBuffer::new(device, label, wgpu::BufferUsages::VERTEX),
            indices: GrowBuffer::new(device, label, wgpu::BufferUsages::INDEX),
            material,
            material_bind,
            triangles: Vec::new(),
            edges: Vec::new(),
            checked_vertices: usize::MAX,
            topology_id: None,
            vertex_normals: VertexNormals::default(),
            belt: wgpu::util::StagingBelt::new(device.clone(), 4 << 20),
            packed: Vec::new(),
            visible: false,
        }
    }

    /// Uploads positions (and normals, unless `flat`), colours, and the triangles if they
    /// changed (`topology_changed`, from [`SurfaceBuffers::same_triangles`]). Returns the number
    /// of buffers re-created and the bounds of the finite positions.
    #[expect(clippy::too_many_arguments)]
    fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        positions: MeshPositions<'_>,
        triangles: &[[u32; 3]],
        topology_changed: bool,
        colors: Option<&[[u8; 4]]>,
        smooth: bool,
        material: MaterialUniform,
    ) -> (u32, Bounds) {
        let mut created = 0;
        if topology_changed {
            self.triangles.clear();
            self.triangles.extend_from_slice(triangles);
            self.edges = unique_edges(triangles);
            self.checked_vertices = positions.len();
            created += u32::from(self.indices.write(device, queue, triangles));
        }
        if smooth {
            if self.vertex_normals.num_vertices() != positions.len() || topology_changed {
                self.vertex_normals = VertexNormals::new(positions.len(), triangles);
            }
            self.vertex_normals.face_normals(positions, triangles);
        }
        let source = VertexSource {
            positions,
            colors,
            normals: smooth.then_some(&self.vertex_normals),
        };
        // Large layers (the skin) are packed in parallel straight into the reused staging belt;
        // small ones (the cage) go through the queue, which costs less than a submission of
        // their own.
        let n = source.len();
        let bounds;
        if n * size_of::<MeshVertex>() >= STAGED_BYTES {
            // The chunks of the previous update were submitted since (the caller's contract):
            // take back those the GPU has finished with (non-blocking).
            self.belt.recall();
            let _ = device.poll(wgpu::PollType::Poll);
            let mut measured = EMPTY_BOUNDS;
            created += u32::from(self.vertices.write_staged_with::<MeshVertex>(
                device,
                encoder,
                &mut self.belt,
                n,
                |dst| measured = source.pack(dst, 0, n),
            ));
            self.belt.finish();
            bounds = measured;
        } else {
            self.packed.resize(n, bytemuck::Zeroable::zeroed());
            bounds = source.pack_into(&mut self.packed);
            created += u32::from(self.vertices.write(device, queue, &self.packed));
        }
        queue.write_buffer(&self.material, 0, bytemuck::bytes_of(&material));
        self.visible = !triangles.is_empty();
        (created, bounds)
    }

    /// Whether `triangles` are the ones last uploaded (then their indices were checked against
    /// `num_vertices` already, if that is unchanged too); equal `topology_id`s vouch for equal
    /// lists.
    fn same_triangles(
        &self,
        triangles: &[[u32; 3]],
        num_vertices: usize,
        topology_id: Option<u64>,
    ) -> bool {
        let same = match (topology_id, self.topology_id) {
            // The caller promises identical lists for equal ids (no 3 MB comparison a frame).
            (Some(a), Some(b)) if a == b => self.triangles.len() == triangles.len(),
            _ => self.triangles == triangles,
        };
        same && self.indices.is_empty() == triangles.is_empty()
            && self.checked_vertices == num_vertices
    }

    fn draw(&self, pass: &mut wgpu::RenderPass<'_>, pipeline: &wgpu::RenderPipeline) {
        if !self.visible {
            return;
        }
        pass.set_pipeline(pipeline);
        pass.set_bind_group(1, &self.material_bind, &[]);
        pass.set_vertex_buffer(
            0,
            self.vertices
                .slice(std::mem::size_of::<MeshVertex>() as u64),
        );
        pass.set_index_buffer(self.indices.slice(12), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.indices.len() * 3, 0, 0..1);
    }
}

/// GPU buffers of every layer of a view.
pub struct SceneBuffers {
    mesh: SurfaceBuffers,
    cage: SurfaceBuffers,
    wireframe: GrowBuffer,
    cage_edges: GrowBuffer,
    cage_edges_hidden: GrowBuffer,
    bones: GrowBuffer,
    handles: GrowBuffer,
    handles_hidden: GrowBuffer,
    joints: GrowBuffer,
    lines: Vec<LineInstance>,
    points: Vec<PointInstance>,
    bounds: Option<(DVec3, DVec3)>,
    ground: bool,
    buffers_created: u64,
}

fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn material(color: [u8; 4], per_vertex: bool, flat: bool, specular: f32) -> MaterialUniform {
    MaterialUniform {
        color: [
            srgb_to_linear(color[0]),
            srgb_to_linear(color[1]),
            srgb_to_linear(color[2]),
            color[3] as f32 / 255.0,
        ],
        params: [
            f32::from(u8::from(per_vertex)),
            f32::from(u8::from(flat)),
            specular,
            0.0,
        ],
    }
}

fn with_alpha(mut c: [u8; 4], alpha: u8) -> [u8; 4] {
    c[3] = alpha;
    c
}

fn check_indices(
    what: &str,
    triangles: &[[u32; 3]],
    num_vertices: usize,
) -> Result<(), RenderError> {
    // The largest index first (a vectorised pass over 3 #F numbers, ≈ 0.1 ms at 266k
    // triangles); the offending triangle is searched only when there is one.
    let largest = triangles.as_flattened().iter().copied().max();
    if largest.is_none_or(|i| (i as usize) < num_vertices) {
        return Ok(());
    }
    match triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&i| i as usize >= num_vertices))
    {
        Some((t, tri)) => Err(RenderError::Geometry(format!(
            "{what} triangle {t} is {tri:?}: expected vertex indices below {num_vertices}"
        ))),
        None => Ok(()),
    }
}

fn check_len(what: &str, len: Option<usize>, expected: usize) -> Result<(), RenderError> {
    match len {
        Some(n) if n != expected => Err(RenderError::Geometry(format!(
            "{what}: expected {expected} colours (one per element), found {n}"
        ))),
        _ => Ok(()),
    }
}

/// Checks a scene's indices and per-element slices before anything is uploaded.
pub fn validate_scene(scene: &Scene<'_>) -> Result<(), RenderError> {
    check_scene(scene, true)
}

/// [`validate_scene`], skipping the mesh's triangle indices unless `mesh_indices` (they were
/// checked when the same triangles were uploaded for as many vertices).
fn check_scene(scene: &Scene<'_>, mesh_indices: bool) -> Result<(), RenderError> {
    if let Some(m) = scene.mesh {
        if mesh_indices {
            check_indices("mesh", m.triangles, m.positions.len())?;
        }
        check_len("mesh colours", m.colors.map(<[_]>::len), m.positions.len())?;
    }
    if let Some(c) = scene.cage {
        check_indices("cage", c.triangles, c.positions.len())?;
        check_len(
            "cage handle colours",
            c.handle_colors.map(<[_]>::len),
            c.positions.len(),
        )?;
    }
    if let Some(s) = scene.skeleton {
        if s.parents.len() != s.joints.len() {
            return Err(RenderError::Geometry(format!(
                "skeleton: expected {} parents (one per joint), found {}",
                s.joints.len(),
                s.parents.len()
            )));
        }
        if let Some((j, p)) = s
            .parents
            .iter()
            .enumerate()
            .find_map(|(j, p)| p.filter(|&p| p >= s.joints.len()).map(|p| (j, p)))
        {
            return Err(RenderError::Geometry(format!(
                "skeleton joint {j} has parent {p}: expected an index below {}",
                s.joints.len()
            )));
        }
        check_len(
            "joint colours",
            s.joint_colors.map(<[_]>::len),
            s.joints.len(),
        )?;
    }
    Ok(())
}

impl SceneBuffers {
    /// Empty buffers on `device` for scenes drawn with `pipelines`.
    pub fn new(device: &wgpu::Device, pipelines: &Pipelines) -> Self {
        let instances = |label| GrowBuffer::new(device, label, wgpu::BufferUsages::VERTEX);
        Self {
            mesh: SurfaceBuffers::new(device, pipelines, "mesh"),
            cage: SurfaceBuffers::new(device, pipelines, "cage faces"),
            wireframe: instances("wireframe"),
            cage_edges: instances("cage edges"),
            cage_edges_hidden: instances("hidden cage edges"),
            bones: instances("bones"),
            handles: instances("cage handles"),
            handles_hidden: instances("hidden cage handles"),
            joints: instances("joints"),
            lines: Vec::new(),
            points: Vec::new(),
            bounds: None,
            ground: false,
            buffers_created: 0,
        }
    }

    /// Uploads `scene` in place and submits the copies. Checks its indices first (nothing is
    /// uploaded on error).
    pub fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene<'_>,
        style: &Style,
    ) -> Result<(), RenderError> {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("scene upload"),
        });
        self.update_into(device, queue, &mut encoder, scene, style)?;
        queue.submit([encoder.finish()]);
        self.recall_staging();
        Ok(())
    }

    /// Takes back the staging memory of the last update once its encoder is submitted (the
    /// next update does it otherwise).
    pub fn recall_staging(&mut self) {
        self.mesh.belt.recall();
        self.cage.belt.recall();
    }

    /// [`SceneBuffers::update`], recording the large copies into `encoder` (e.g. the one that
    /// then renders the view: one submission per view, and the driver's work is not counted as
    /// upload). `encoder` must be submitted before the next update. Small layers are written
    /// through the queue, which orders them before `encoder`'s commands.
    pub fn update_into(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &Scene<'_>,
        style: &Style,
    ) -> Result<(), RenderError> {
        let (positions, triangles) = scene.mesh.map_or((MeshPositions::F64(&[]), &[][..]), |m| {
            (m.positions, m.triangles)
        });
        let topology_id = scene.mesh.and_then(|m| m.topology_id);
        let mesh_topology_changed =
            !self
                .mesh
                .same_triangles(triangles, positions.len(), topology_id);
        check_scene(scene, mesh_topology_changed)?;
        let cage_topology_changed = scene.cage.is_none_or(|c| {
            !self
                .cage
                .same_triangles(c.triangles, c.positions.len(), None)
        });
        let mut created = 0u32;
        let mesh_material = material(
            style.mesh,
            scene.mesh.is_some_and(|m| m.colors.is_some()),
            scene.mesh.is_some_and(|m| m.flat),
            0.25,
        );
        let (mesh_created, mesh_bounds) = self.mesh.update(
            device,
            queue,
            encoder,
            positions,
            triangles,
            mesh_topology_changed,
            scene.mesh.and_then(|m| m.colors),
            !scene.mesh.is_some_and(|m| m.flat),
            mesh_material,
        );
        created += mesh_created;
        self.mesh.topology_id = topology_id;
        let (cage_positions, cage_triangles) = scene
            .cage
            .map_or((&[][..], &[][..]), |c| (c.positions, c.triangles));
        created += self
            .cage
            .update(
                device,
                queue,
                encoder,
                MeshPositions::F64(cage_positions),
                cage_triangles,
                cage_topology_changed,
                None,
                false,
                material(style.cage_faces, false, true, 0.0),
            )
            .0;

        let s = style.scale;
        let lines = &mut self.lines;
        let line = |a: DVec3, b: DVec3, color, width: f32, bias| LineInstance {
            a: a.as_vec3().to_array(),
            b: b.as_vec3().to_array(),
            color,
            style: [width * s, bias],
        };
        // Wireframe.
        lines.clear();
        if scene.mesh.is_some_and(|m| m.wireframe) {
            lines.extend(self.mesh.edges.iter().map(|&[a, b]| {
                line(
                    positions.get(a as usize),
                    positions.get(b as usize),
                    style.wireframe,
                    0.8,
                    2e-5,
                )
            }));
        }
        created += u32::from(self.wireframe.write(device, queue, lines));
        // Cage edges, visible then hidden.
        lines.clear();
        lines.extend(self.cage.edges.iter().map(|&[a, b]| {
            line(
                cage_positions[a as usize],
                cage_positions[b as usize],
                style.cage_edges,
                style.line_width,
                1e-4,
            )
        }));
        created += u32::from(self.cage_edges.write(device, queue, lines));
        lines
            .iter_mut()
            .for_each(|l| l.color[3] = style.hidden_alpha);
        created += u32::from(self.cage_edges_hidden.write(device, queue, lines));
        // Bones.
        lines.clear();
        if let Some(sk) = scene.skeleton {
            lines.extend(sk.parents.iter().enumerate().filter_map(|(j, p)| {
                p.map(|p| {
                    line(
                        sk.joints[p],
                        sk.joints[j],
                        style.bones,
                        style.bone_width,
                        0.0,
                    )
                })
            }));
        }
        created += u32::from(self.bones.write(device, queue, lines));

        let points = &mut self.points;
        let point = |c: DVec3, color, radius: f32| PointInstance {
            centre: c.as_vec3().to_array(),
            style: [radius * s, 2e-4],
            color,
        };
        points.clear();
        if let Some(c) = scene.cage {
            points.extend(c.positions.iter().enumerate().map(|(k, p)| {
                point(
                    *p,
                    c.handle_colors.map_or(style.cage_handles, |h| h[k]),
                    style.handle_radius,
                )
            }));
        }
        created += u32::from(self.handles.write(device, queue, points));
        points
            .iter_mut()
            .for_each(|p| p.color = with_alpha(p.color, style.hidden_alpha));
        created += u32::from(self.handles_hidden.write(device, queue, points));
        points.clear();
        if let Some(sk) = scene.skeleton {
            points.extend(sk.joints.iter().enumerate().map(|(j, p)| {
                point(
                    *p,
                    sk.joint_colors.map_or(style.joints, |c| c[j]),
                    style.joint_radius,
                )
            }));
        }
        created += u32::from(self.joints.write(device, queue, points));

        self.bounds = scene.bounds_with_mesh(mesh_bounds);
        self.ground = scene.ground;
        self.buffers_created += u64::from(created);
        Ok(())
    }

    /// Bounds of the last uploaded scene.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        self.bounds
    }

    /// Whether the last scene asked for a ground.
    pub fn ground(&self) -> bool {
        self.ground
    }

    /// GPU buffers created so far (by growth); stays constant while frames of the same size
    /// are uploaded.
    pub fn buffers_created(&self) -> u64 {
        self.buffers_created
    }

    /// Records the draws in back-to-front layer order: skin, ground, wireframe, hidden cage
    /// parts, cage faces, cage edges and handles, skeleton on top.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, pipelines: &Pipelines) {
        self.mesh.draw(pass, &pipelines.mesh_opaque);
        if self.ground {
            pass.set_pipeline(&pipelines.ground);
            pass.draw(0..6, 0..1);
        }
        let line_size = std::mem::size_of::<LineInstance>() as u64;
        let point_size = std::mem::size_of::<PointInstance>() as u64;
        let instanced = |pass: &mut wgpu::RenderPass<'_>, pipeline, buffer: &GrowBuffer, size| {
            if !buffer.is_empty() {
                pass.set_pipeline(pipeline);
                pass.set_vertex_buffer(0, buffer.slice(size));
                pass.draw(0..6, 0..buffer.len());
            }
        };
        instanced(pass, &pipelines.lines_tested, &self.wireframe, line_size);
        instanced(
            pass,
            &pipelines.lines_on_top,
            &self.cage_edges_hidden,
            line_size,
        );
        instanced(
            pass,
            &pipelines.points_on_top,
            &self.handles_hidden,
            point_size,
        );
        self.cage.draw(pass, &pipelines.mesh_translucent);
        instanced(pass, &pipelines.lines_tested, &self.cage_edges, line_size);
        instanced(pass, &pipelines.points_tested, &self.handles, point_size);
        instanced(pass, &pipelines.lines_on_top, &self.bones, line_size);
        instanced(pass, &pipelines.points_on_top, &self.joints, point_size);
    }
}
