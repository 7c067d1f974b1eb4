//! The flags that say how to read a pose file, shared by every command that reads one.

use std::path::Path;

use anyhow::{Result, bail};
use clap::Args;
use loops_core::{MetricSpec, Trajectory};

#[derive(Debug, Args)]
pub(crate) struct InputArgs {
    /// File format: tum, csv, kitti, euroc, tuc, g2o, mcap (default: from the extension and
    /// first line).
    #[arg(long)]
    format: Option<String>,
    /// MCAP topic to read (default: the one topic with poses; `loops info` lists them).
    #[arg(long)]
    topic: Option<String>,
    /// MCAP time of each pose: header (the message stamp), log or publish.
    #[arg(long)]
    time: Option<String>,
    /// Parent and child frame of a transform topic (TF), e.g. odom,base_link.
    #[arg(long, value_delimiter = ',', value_name = "PARENT,CHILD")]
    frames: Option<Vec<String>>,
    /// For files without times (KITTI poses, pose graphs): pose i at i / RATE_HZ seconds.
    #[arg(long, value_name = "RATE_HZ")]
    rate_hz: Option<f64>,
    /// Keep only these two position axes, e.g. 0,2 for KITTI's ground plane (x-z).
    #[arg(long, value_delimiter = ',', value_name = "A,B")]
    axes: Option<Vec<usize>>,
}

impl InputArgs {
    /// The options of `loops_io` these flags ask for.
    pub(crate) fn options(&self) -> Result<loops_io::ReadOptions> {
        let mut mcap = loops_io::McapOptions::default();
        if let Some(topic) = &self.topic {
            mcap = mcap.topic(topic.clone());
        }
        if let Some(time) = &self.time {
            mcap = mcap.time(time.parse()?);
        }
        match self.frames.as_deref() {
            None => {}
            Some([parent, child]) => mcap = mcap.frames(parent.clone(), child.clone()),
            Some(other) => bail!("--frames takes a parent and a child frame, got {other:?}"),
        }
        let mut options = loops_io::ReadOptions::default().mcap(mcap);
        if let Some(format) = &self.format {
            options = options.format(format.parse()?);
        }
        if let Some(rate) = self.rate_hz {
            options = options.timing(loops_io::Timing::RateHz(rate));
        }
        Ok(options)
    }

    /// Reads `file` as the trajectory `spec` needs.
    pub(crate) fn read(&self, file: &Path, spec: &MetricSpec) -> Result<Trajectory> {
        Ok(self.read_table(file, spec)?.1)
    }

    /// Reads `file`: the poses as read (orientations included) and the trajectory `spec` needs.
    pub(crate) fn read_table(&self, file: &Path, spec: &MetricSpec) -> Result<(loops_io::PoseTable, Trajectory)> {
        let axes = match self.axes.as_deref() {
            None => None,
            Some(&[a, b]) => Some([a, b]),
            Some(other) => bail!("--axes takes two axis indices, got {other:?}"),
        };
        let options = self.options()?;
        let table = loops_io::read_trajectory_with(file, &options)?;
        let traj = table.to_trajectory_for(spec, axes)?;
        Ok((table, traj))
    }
}
