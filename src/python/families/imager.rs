//! `vrpn.ImagerRemote`: an image stream's description, frames and regions.

use std::rc::Rc;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList};

use super::super::callbacks::{run, Owner};
use super::super::owned::Owned;
use super::super::remote::{Remote, RemoteLike};
use super::super::server::{close_held, held, Held, Server};
use super::super::to_py;
use crate::devices::base::RemoteCore;
use crate::devices::imager::{
    ChannelDescription, DiscardedFramesReport, Extent, FrameReport, ImagerDescription,
    ImagerRegion as RustRegion, ValueType,
};
use crate::dispatch::HandlerId;

type Imager = crate::devices::imager::ImagerRemote;

impl RemoteLike for Imager {
    fn core(&self) -> &RemoteCore {
        self
    }
    fn remove(&self, id: HandlerId) -> bool {
        self.remove_callback(id)
    }
}

fn type_name(t: ValueType) -> &'static str {
    match t {
        ValueType::U8 => "u8",
        ValueType::U16 => "u16",
        ValueType::U12In16 => "u12in16",
        ValueType::F32 => "f32",
    }
}

fn ranges(e: &Extent) -> ((u16, u16), (u16, u16), (u16, u16)) {
    ((e.c_min, e.c_max), (e.r_min, e.r_max), (e.d_min, e.d_max))
}

/// One region of one channel, copied out of the message.
#[pyclass(frozen, module = "vrpn", name = "ImagerRegion")]
pub(crate) struct ImagerRegion {
    channel: usize,
    extent: Extent,
    value_type: ValueType,
    data: Vec<u8>,
    time: f64,
    sender_time: f64,
    arrival: f64,
}

impl ImagerRegion {
    fn new(r: &RustRegion<'_>) -> ImagerRegion {
        ImagerRegion {
            channel: r.channel,
            extent: r.extent,
            value_type: r.value_type,
            data: r.data.to_vec(),
            time: r.time.as_secs_f64(),
            sender_time: r.sender_time.as_secs_f64(),
            arrival: r.arrival.as_secs_f64(),
        }
    }
}

#[pymethods]
impl ImagerRegion {
    /// Channel index in the description.
    #[getter]
    fn channel(&self) -> usize {
        self.channel
    }
    /// (first, last) column, inclusive.
    #[getter]
    fn columns(&self) -> (u16, u16) {
        ranges(&self.extent).0
    }
    /// (first, last) row, inclusive.
    #[getter]
    fn rows(&self) -> (u16, u16) {
        ranges(&self.extent).1
    }
    /// (first, last) depth, inclusive.
    #[getter]
    fn depths(&self) -> (u16, u16) {
        ranges(&self.extent).2
    }
    /// "u8", "u16", "u12in16" or "f32".
    #[getter]
    fn value_type(&self) -> &'static str {
        type_name(self.value_type)
    }
    /// The pixels as on the wire: little-endian, columns fastest, then rows, then depths
    /// (`numpy.frombuffer(r.data, "<u2")` for "u16").
    #[getter]
    fn data<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.data)
    }
    /// The pixels as a list of numbers (ints, or floats for "f32").
    fn values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let size = self.value_type.size();
        let chunks = self.data.chunks_exact(size);
        match self.value_type {
            ValueType::U8 => PyList::new(py, self.data.iter().copied()),
            ValueType::U16 | ValueType::U12In16 => {
                PyList::new(py, chunks.map(|b| u16::from_le_bytes([b[0], b[1]])))
            }
            ValueType::F32 => PyList::new(
                py,
                chunks.map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            ),
        }
    }
    /// Pixels in the region.
    fn __len__(&self) -> usize {
        self.extent.len()
    }
    /// The server's time stamp, seconds since the epoch.
    #[getter]
    fn time(&self) -> f64 {
        self.time
    }
    /// The time stamp exactly as the server wrote it.
    #[getter]
    fn sender_time(&self) -> f64 {
        self.sender_time
    }
    /// When it arrived here (the `mainloop()` pass that read it).
    #[getter]
    fn arrival(&self) -> f64 {
        self.arrival
    }
    fn __repr__(&self) -> String {
        let (c, r, d) = ranges(&self.extent);
        format!(
            "ImagerRegion(channel={}, columns={c:?}, rows={r:?}, depths={d:?}, value_type={:?})",
            self.channel,
            type_name(self.value_type)
        )
    }
}

/// One channel of the description.
#[pyclass(frozen, module = "vrpn", name = "ImagerChannel")]
pub(crate) struct ImagerChannel(ChannelDescription);

#[pymethods]
impl ImagerChannel {
    /// The channel's name.
    #[getter]
    fn name(&self) -> String {
        self.0.name.to_string_lossy()
    }
    /// Its units.
    #[getter]
    fn units(&self) -> String {
        self.0.units.to_string_lossy()
    }
    /// Smallest raw value.
    #[getter]
    fn min_val(&self) -> f32 {
        self.0.min_val
    }
    /// Largest raw value.
    #[getter]
    fn max_val(&self) -> f32 {
        self.0.max_val
    }
    /// Physical value = raw × scale + offset.
    #[getter]
    fn scale(&self) -> f32 {
        self.0.scale
    }
    /// Physical value = raw × scale + offset.
    #[getter]
    fn offset(&self) -> f32 {
        self.0.offset
    }
    fn __repr__(&self) -> String {
        format!(
            "ImagerChannel(name={:?}, units={:?})",
            self.name(),
            self.units()
        )
    }
}

/// The image's size and channel count.
#[pyclass(frozen, module = "vrpn", name = "ImagerDescription")]
pub(crate) struct Description(ImagerDescription);

#[pymethods]
impl Description {
    /// Columns.
    #[getter]
    fn cols(&self) -> i32 {
        self.0.cols
    }
    /// Rows.
    #[getter]
    fn rows(&self) -> i32 {
        self.0.rows
    }
    /// Depth.
    #[getter]
    fn depth(&self) -> i32 {
        self.0.depth
    }
    /// Number of channels.
    #[getter]
    fn channels(&self) -> usize {
        self.0.channels
    }
    /// The server's time stamp.
    #[getter]
    fn time(&self) -> f64 {
        self.0.time.as_secs_f64()
    }
    fn __repr__(&self) -> String {
        let d = &self.0;
        format!(
            "ImagerDescription(cols={}, rows={}, depth={}, channels={})",
            d.cols, d.rows, d.depth, d.channels
        )
    }
}

/// A begin-frame or end-frame.
#[pyclass(frozen, module = "vrpn", name = "ImagerFrame")]
pub(crate) struct Frame(FrameReport);

#[pymethods]
impl Frame {
    /// (first, last) column.
    #[getter]
    fn columns(&self) -> (u16, u16) {
        ranges(&self.0.extent).0
    }
    /// (first, last) row.
    #[getter]
    fn rows(&self) -> (u16, u16) {
        ranges(&self.0.extent).1
    }
    /// (first, last) depth.
    #[getter]
    fn depths(&self) -> (u16, u16) {
        ranges(&self.0.extent).2
    }
    /// Counts the frames begun (or ended), 1 for the first.
    #[getter]
    fn seq(&self) -> u64 {
        self.0.seq
    }
    /// The server's time stamp.
    #[getter]
    fn time(&self) -> f64 {
        self.0.time.as_secs_f64()
    }
    /// When it arrived here.
    #[getter]
    fn arrival(&self) -> f64 {
        self.0.arrival.as_secs_f64()
    }
    fn __repr__(&self) -> String {
        let (c, r, _) = ranges(&self.0.extent);
        format!("ImagerFrame(seq={}, columns={c:?}, rows={r:?})", self.0.seq)
    }
}

/// A discarded-frames notice.
#[pyclass(frozen, module = "vrpn", name = "ImagerDiscarded")]
pub(crate) struct Discarded(DiscardedFramesReport);

#[pymethods]
impl Discarded {
    /// Frames dropped (0: some, count unknown).
    #[getter]
    fn count(&self) -> u16 {
        self.0.count
    }
    /// The server's time stamp.
    #[getter]
    fn time(&self) -> f64 {
        self.0.time.as_secs_f64()
    }
}

/// Client of an imager: `ImagerRemote("TestImage@host")`.
#[pyclass(extends = Remote, module = "vrpn", name = "ImagerRemote")]
pub(crate) struct ImagerRemote;

#[pymethods]
impl ImagerRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Imager::new(name).map_err(to_py)?;
        Ok((ImagerRemote, Remote::new("ImagerRemote", inner)))
    }

    /// Calls `f(region)` for every region (once a description arrived). Returns a handle.
    fn on_region(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let i = base.inner::<Imager>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            i.on_region(move |r| slot.call_with(|| ImagerRegion::new(r)))
        })
    }

    /// Calls `f(description)` for every description. Returns a handle.
    fn on_description(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let i = base.inner::<Imager>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            i.on_description(move |d| slot.call_with(|| Description(*d)))
        })
    }

    /// Calls `f(frame)` at the beginning of every frame. Returns a handle.
    fn on_begin_frame(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let i = base.inner::<Imager>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            i.on_begin_frame(move |r| slot.call_with(|| Frame(*r)))
        })
    }

    /// Calls `f(frame)` at the end of every frame. Returns a handle.
    fn on_end_frame(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let i = base.inner::<Imager>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            i.on_end_frame(move |r| slot.call_with(|| Frame(*r)))
        })
    }

    /// Calls `f(notice)` for every discarded-frames notice. Returns a handle.
    fn on_discarded_frames(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let i = base.inner::<Imager>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            i.on_discarded_frames(move |d| slot.call_with(|| Discarded(*d)))
        })
    }

    /// Asks the server for at most `frames` more frames; negative lifts the limit.
    fn throttle_sender(slf: PyRef<'_, Self>, frames: i32) -> PyResult<()> {
        let i = slf.as_super().inner::<Imager>()?;
        i.throttle_sender(frames).map_err(to_py)
    }

    /// The latest description, None before one arrived.
    #[getter]
    fn description(slf: PyRef<'_, Self>) -> PyResult<Option<Description>> {
        Ok(slf
            .as_super()
            .inner::<Imager>()?
            .description()
            .map(Description))
    }

    /// Channel `i` of the latest description, None if it has none.
    fn channel(slf: PyRef<'_, Self>, i: usize) -> PyResult<Option<ImagerChannel>> {
        Ok(slf
            .as_super()
            .inner::<Imager>()?
            .channel(i)
            .map(ImagerChannel))
    }

    /// The index of the channel named `name`, None if there is none.
    fn channel_index(slf: PyRef<'_, Self>, name: &str) -> PyResult<Option<usize>> {
        Ok(slf.as_super().inner::<Imager>()?.channel_index(name))
    }

    /// The newest end-frame if it arrived since the last call, else None.
    fn take_end_frame(slf: PyRef<'_, Self>) -> PyResult<Option<Frame>> {
        Ok(slf
            .as_super()
            .inner::<Imager>()?
            .take_end_frame()
            .map(Frame))
    }

    /// Regions delivered so far.
    #[getter]
    fn regions_received(slf: PyRef<'_, Self>) -> PyResult<u64> {
        Ok(slf.as_super().inner::<Imager>()?.regions_received())
    }

    /// Frames the server said it discarded.
    #[getter]
    fn frames_discarded(slf: PyRef<'_, Self>) -> PyResult<u64> {
        Ok(slf.as_super().inner::<Imager>()?.frames_discarded())
    }
}

type RustServer = crate::devices::imager::ImagerServer;

/// An imager on a `Server`: `ImagerServer(server, "Cam0", cols, rows, depth=1)`.
#[pyclass(module = "vrpn", name = "ImagerServer")]
pub(crate) struct ImagerServer {
    held: Owned<Rc<Held<RustServer>>>,
}

impl ImagerServer {
    fn dev(&self) -> PyResult<Rc<RustServer>> {
        held(&self.held, "ImagerServer")
    }
}

#[allow(clippy::too_many_arguments)]
fn extent(c_min: u16, c_max: u16, r_min: u16, r_max: u16, d_min: u16, d_max: u16) -> Extent {
    Extent {
        c_min,
        c_max,
        r_min,
        r_max,
        d_min,
        d_max,
    }
}

#[pymethods]
impl ImagerServer {
    #[new]
    #[pyo3(signature = (server, name, cols, rows, depth = 1))]
    fn new(
        server: PyRef<'_, Server>,
        name: &str,
        cols: i32,
        rows: i32,
        depth: i32,
    ) -> PyResult<Self> {
        if cols <= 0 || rows <= 0 || depth <= 0 {
            return Err(PyValueError::new_err(format!(
                "image size {cols}×{rows}×{depth} must be positive"
            )));
        }
        let held = server.adopt(|conn| RustServer::new(name, conn, cols, rows, depth))?;
        Ok(ImagerServer { held })
    }

    /// Adds a channel; returns its index.
    #[pyo3(signature = (name, units = "", min_val = 0.0, max_val = 255.0, scale = 1.0, offset = 0.0))]
    fn add_channel(
        &self,
        name: &str,
        units: &str,
        min_val: f32,
        max_val: f32,
        scale: f32,
        offset: f32,
    ) -> PyResult<usize> {
        self.dev()?
            .add_channel(name, units, min_val, max_val, scale, offset)
            .map_err(to_py)
    }

    /// Starts a frame over the extent; False when the clients' throttle drops it.
    #[pyo3(signature = (c_min, c_max, r_min, r_max, d_min = 0, d_max = 0, time = None))]
    #[allow(clippy::too_many_arguments)]
    fn send_begin_frame(
        &self,
        c_min: u16,
        c_max: u16,
        r_min: u16,
        r_max: u16,
        d_min: u16,
        d_max: u16,
        time: Option<f64>,
    ) -> PyResult<bool> {
        let d = self.dev()?;
        let t = time.map(super::super::header_time).transpose()?;
        run(|| d.send_begin_frame(&extent(c_min, c_max, r_min, r_max, d_min, d_max), t))
    }

    /// Ends a frame; False while frames are dropped.
    #[pyo3(signature = (c_min, c_max, r_min, r_max, d_min = 0, d_max = 0, time = None))]
    #[allow(clippy::too_many_arguments)]
    fn send_end_frame(
        &self,
        c_min: u16,
        c_max: u16,
        r_min: u16,
        r_max: u16,
        d_min: u16,
        d_max: u16,
        time: Option<f64>,
    ) -> PyResult<bool> {
        let d = self.dev()?;
        let t = time.map(super::super::header_time).transpose()?;
        run(|| d.send_end_frame(&extent(c_min, c_max, r_min, r_max, d_min, d_max), t))
    }

    /// Sends a region of channel `channel`: `data` holds its pixels packed, columns fastest
    /// (bytes for "u8"; little-endian for "u16" and "f32", as `numpy.tobytes()` gives).
    /// False while frames are dropped.
    #[pyo3(signature = (channel, c_min, c_max, r_min, r_max, data, value_type = "u8", d_min = 0, d_max = 0, time = None))]
    #[allow(clippy::too_many_arguments)]
    fn send_region(
        &self,
        channel: usize,
        c_min: u16,
        c_max: u16,
        r_min: u16,
        r_max: u16,
        data: &[u8],
        value_type: &str,
        d_min: u16,
        d_max: u16,
        time: Option<f64>,
    ) -> PyResult<bool> {
        let d = self.dev()?;
        let e = extent(c_min, c_max, r_min, r_max, d_min, d_max);
        let t = time.map(super::super::header_time).transpose()?;
        match value_type {
            "u8" => run(|| d.send_region_packed(channel, &e, data, t)),
            "u16" => {
                let v: Vec<u16> = data
                    .chunks_exact(2)
                    .map(|b| u16::from_le_bytes([b[0], b[1]]))
                    .collect();
                run(|| d.send_region_packed(channel, &e, &v, t))
            }
            "f32" => {
                let v: Vec<f32> = data
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect();
                run(|| d.send_region_packed(channel, &e, &v, t))
            }
            other => Err(PyValueError::new_err(format!(
                "value_type must be \"u8\", \"u16\" or \"f32\", got {other:?}"
            ))),
        }
    }

    /// Frames the clients' throttle still allows (-1: no limit).
    #[getter]
    fn frames_to_send(&self) -> PyResult<i32> {
        Ok(self.dev()?.frames_to_send())
    }

    /// Stops serving the imager.
    fn close(&self) -> PyResult<()> {
        close_held(&self.held, "ImagerServer")
    }
}

pub(super) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ImagerServer>()?;
    m.add_class::<ImagerRemote>()?;
    m.add_class::<ImagerRegion>()?;
    m.add_class::<ImagerChannel>()?;
    m.add_class::<Description>()?;
    m.add_class::<Frame>()?;
    m.add_class::<Discarded>()
}
