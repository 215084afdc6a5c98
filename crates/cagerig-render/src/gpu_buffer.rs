//! A GPU buffer written in place every frame and re-created only when its content outgrows it.

use bytemuck::Pod;

/// A vertex/index/instance buffer with spare capacity.
pub struct GrowBuffer {
    label: &'static str,
    usage: wgpu::BufferUsages,
    buffer: wgpu::Buffer,
    capacity: u64,
    /// Elements written by the last [`write`](Self::write).
    len: u32,
}

impl GrowBuffer {
    pub fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages) -> Self {
        let usage = usage | wgpu::BufferUsages::COPY_DST;
        let capacity = 256;
        Self {
            label,
            usage,
            buffer: create(device, label, usage, capacity),
            capacity,
            len: 0,
        }
    }

    /// Makes room for `size` bytes; true when the buffer had to be re-created (capacity grows by
    /// 1.5× to absorb small growth).
    fn reserve(&mut self, device: &wgpu::Device, size: u64) -> bool {
        let recreated = size > self.capacity;
        if recreated {
            self.capacity = (size + size / 2).next_multiple_of(256);
            self.buffer = create(device, self.label, self.usage, self.capacity);
        }
        recreated
    }

    /// Writes `data` at offset 0 through the queue. Returns `true` when the buffer had to be
    /// re-created (first use of a larger size; capacity grows by 1.5× to absorb small growth).
    pub fn write<T: Pod>(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        data: &[T],
    ) -> bool {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        // Buffer writes must be a multiple of 4 bytes.
        let size = (bytes.len() as u64).next_multiple_of(4);
        let recreated = self.reserve(device, size);
        if !bytes.is_empty() {
            if bytes.len().is_multiple_of(4) {
                queue.write_buffer(&self.buffer, 0, bytes);
            } else {
                let mut padded = bytes.to_vec();
                padded.resize(size as usize, 0);
                queue.write_buffer(&self.buffer, 0, &padded);
            }
        }
        self.len = data.len() as u32;
        recreated
    }

    /// Records into `encoder` the write of `len` elements of `T` at offset 0 through `belt`,
    /// whose staging chunks are reused from frame to frame (`Queue::write_buffer` allocates
    /// fresh staging memory on every call, and the kernel zeroing those pages was ≈ 20 % of a
    /// 133k-vertex upload). `fill` writes the `len · size_of::<T>()` bytes straight into the
    /// mapped staging memory (no copy of the whole content). The caller calls `belt.finish()`
    /// before submitting `encoder`, and `belt.recall()` after. Returns `true` when the buffer had
    /// to be re-created.
    pub fn write_staged_with<T: Pod>(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        belt: &mut wgpu::util::StagingBelt,
        len: usize,
        fill: impl FnOnce(wgpu::WriteOnly<'_, [u8]>),
    ) -> bool {
        let bytes = len * size_of::<T>();
        let size = (bytes as u64).next_multiple_of(4);
        let recreated = self.reserve(device, size);
        if let Some(size) = wgpu::BufferSize::new(size) {
            let mut view = belt.write_buffer(encoder, &self.buffer, 0, size);
            let mut whole = view.slice(..);
            if let Some(mut padding) = whole.split_off(bytes..) {
                padding.fill(0);
            }
            fill(whole);
        }
        self.len = len as u32;
        recreated
    }

    /// Number of elements of the last write.
    pub fn len(&self) -> u32 {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The written part, for binding.
    pub fn slice(&self, element_size: u64) -> wgpu::BufferSlice<'_> {
        self.buffer.slice(..(self.len as u64 * element_size).max(4))
    }
}

fn create(
    device: &wgpu::Device,
    label: &str,
    usage: wgpu::BufferUsages,
    size: u64,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}
