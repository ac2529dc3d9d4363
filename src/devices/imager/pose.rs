//! Where an image lies in space (C++ `vrpn_ImagerPose`): origin and the spans of the image
//! along columns, rows and depth, sent when a client connects or pings and on every change.

use std::cell::Cell;
use std::ops::Deref;
use std::rc::Rc;

use crate::connection::{Connection, ConnectionEvent};
use crate::devices::base::{self, BaseIds, RemoteCore};
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::time::TimeVal;
use crate::wire::class;
use crate::wire::payload::imager::{PoseDescription, POSE_DESCRIPTION};

/// The place of an image, in meters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImagerPose {
    /// The outer corner of pixel (0,0,0).
    pub origin: [f64; 3],
    /// From the origin to one pixel past the last column (the image's whole width).
    pub d_col: [f64; 3],
    /// From the origin to one pixel past the last row.
    pub d_row: [f64; 3],
    /// From the origin to one pixel past the last depth.
    pub d_depth: [f64; 3],
}

impl ImagerPose {
    /// The centre of pixel (`col`, `row`, `depth`) of a `cols` × `rows` × `depth_count`
    /// image in this place (C++ `compute_pixel_center`); `None` for a pixel outside it.
    pub fn pixel_center(
        &self,
        cols: i32,
        rows: i32,
        depth_count: i32,
        col: u16,
        row: u16,
        depth: u16,
    ) -> Option<[f64; 3]> {
        if i32::from(col) >= cols || i32::from(row) >= rows || i32::from(depth) >= depth_count {
            return None;
        }
        let (sc, sr, sd) = (
            (0.5 + f64::from(col)) / f64::from(cols),
            (0.5 + f64::from(row)) / f64::from(rows),
            (0.5 + f64::from(depth)) / f64::from(depth_count),
        );
        Some(std::array::from_fn(|i| {
            self.origin[i] + sc * self.d_col[i] + sr * self.d_row[i] + sd * self.d_depth[i]
        }))
    }

    fn to_wire(self) -> PoseDescription {
        PoseDescription {
            origin: self.origin,
            d_depth: self.d_depth,
            d_row: self.d_row,
            d_col: self.d_col,
        }
    }

    fn from_wire(p: &PoseDescription) -> ImagerPose {
        ImagerPose {
            origin: p.origin,
            d_col: p.d_col,
            d_row: p.d_row,
            d_depth: p.d_depth,
        }
    }
}

/// A pose as the remote received it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImagerPoseReport {
    /// The server's time stamp.
    pub time: TimeVal,
    /// When it arrived here.
    pub arrival: TimeVal,
    /// The place.
    pub pose: ImagerPose,
}

fn send_pose(
    conn: &Connection,
    type_id: TypeId,
    sender: SenderId,
    pose: ImagerPose,
) -> Result<(), Error> {
    let mut buf = [0u8; PoseDescription::LEN];
    pose.to_wire().encode(&mut buf);
    conn.pack_message(conn.now().wall, type_id, sender, &buf, class::RELIABLE)
}

/// Server half: announces where the image lies.
pub struct ImagerPoseServer {
    conn: Connection,
    base: BaseIds,
    description: TypeId,
    pose: Rc<Cell<ImagerPose>>,
}

impl ImagerPoseServer {
    /// Registers `device` on `conn` with its place.
    pub fn new(
        device: &str,
        conn: &Connection,
        pose: ImagerPose,
    ) -> Result<ImagerPoseServer, Error> {
        let (base, description) =
            base::register_server(conn, device, |c| c.register_type(POSE_DESCRIPTION))?;
        let pose = Rc::new(Cell::new(pose));
        let p = pose.clone();
        conn.register_handler(base.ping, SenderFilter::Only(base.sender), move |m| {
            let _ = send_pose(m.connection(), description, base.sender, p.get());
        });
        let (p, weak) = (pose.clone(), conn.downgrade());
        conn.on_event(ConnectionEvent::GotConnection, move || {
            if let Some(c) = weak.upgrade() {
                let _ = send_pose(&c, description, base.sender, p.get());
            }
        });
        Ok(ImagerPoseServer {
            conn: conn.clone(),
            base,
            description,
            pose,
        })
    }

    /// The place announced.
    pub fn pose(&self) -> ImagerPose {
        self.pose.get()
    }

    /// Changes the place and sends it (C++ `set_range`).
    pub fn set_pose(&self, pose: ImagerPose) -> Result<(), Error> {
        self.pose.set(pose);
        self.send_description()
    }

    /// Sends the place now.
    pub fn send_description(&self) -> Result<(), Error> {
        send_pose(
            &self.conn,
            self.description,
            self.base.sender,
            self.pose.get(),
        )
    }
}

/// Client half: learns where the image lies.
pub struct ImagerPoseRemote {
    core: RemoteCore,
    latest: Rc<Cell<Option<ImagerPoseReport>>>,
    reports: Rc<CallbackList<ImagerPoseReport>>,
}

impl Deref for ImagerPoseRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl ImagerPoseRemote {
    /// Opens `Device@location`.
    pub fn new(name: &str) -> Result<ImagerPoseRemote, Error> {
        let (device, conn) = RemoteCore::open(name)?;
        Self::on_connection(&device, &conn)
    }

    /// A remote for `device` on an existing connection.
    pub fn on_connection(device: &str, conn: &Connection) -> Result<ImagerPoseRemote, Error> {
        let (mut core, description) =
            RemoteCore::new(device, conn, |c| c.register_type(POSE_DESCRIPTION))?;
        let latest = Rc::new(Cell::new(None));
        let reports: Rc<CallbackList<ImagerPoseReport>> = Rc::new(CallbackList::default());
        let (l, r) = (latest.clone(), reports.clone());
        core.handle(description, move |m| {
            if let Ok(p) = PoseDescription::decode(m.payload) {
                let report = ImagerPoseReport {
                    time: m.time,
                    arrival: m.arrived(),
                    pose: ImagerPose::from_wire(&p),
                };
                l.set(Some(report));
                r.call(&report);
            }
        });
        Ok(ImagerPoseRemote {
            core,
            latest,
            reports,
        })
    }

    /// The latest place, once the server described it.
    pub fn pose(&self) -> Option<ImagerPoseReport> {
        self.latest.get()
    }

    /// Calls `f` with each description.
    pub fn on_description(&self, f: impl FnMut(&ImagerPoseReport) + 'static) -> HandlerId {
        self.reports.add(f)
    }

    /// Removes a callback [`on_description`](Self::on_description) returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.reports.remove(id)
    }
}
