//! Transform trees (ROS TF): the pose of one frame in another, composed along the chain of
//! transforms that links them, at each time the chain's lowest moving link was stamped.
//!
//! A TF topic holds transforms `parent → child` (the pose of `child` in `parent`); every frame
//! has at most one parent, so the frames form a tree (`map → odom → base_link → velodyne`).
//! The pose of `child` in `parent` is `T(a → parent)⁻¹ T(a → child)`, where `a` is the lowest
//! frame above both, each `T` the product of the transforms down the chain.
//!
//! The rule for times: the poses are those of the moving (dynamic) link nearest to `child`
//! (on the way up from `child`, else on the way up from `parent`), one pose per transform of
//! it, at its stamp. Every other moving link is interpolated at that stamp between its two
//! transforms around it: positions linearly, rotations by slerp. A stamp outside the span of
//! another moving link's transforms has no pose (TF does not extrapolate either): it is left
//! out. Static transforms (`/tf_static`) hold at every time; a link sent several times on the
//! static topic takes its last transform.

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::table::MessageRef;

/// One transform: the pose of a link's child in its parent at `stamp_ns`, with its message.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Row {
    pub(crate) stamp_ns: i64,
    pub(crate) position: [f64; 3],
    pub(crate) orientation: [f64; 4],
    pub(crate) source: MessageRef,
}

/// The transforms of one link `parent → child`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Link<'r> {
    pub(crate) parent: &'r str,
    pub(crate) child: &'r str,
    /// Sorted by stamp.
    pub(crate) rows: &'r [Row],
    /// From a static topic: holds at every time.
    pub(crate) is_static: bool,
}

/// The poses of `child` in `parent` composed from `links` (see the module docs), sorted by
/// stamp, each with the message of the moving link that timed it.
///
/// # Errors
/// A one-line message when the frames are not linked (naming the frame at the top of each
/// chain, whose parent no transform gives), when a frame has two parents, when every link of
/// the chain is static, or when no stamp of the timing link falls within the span of the other
/// moving links.
pub(crate) fn compose(links: &[Link<'_>], parent: &str, child: &str) -> Result<Vec<Row>, String> {
    let mut frames: Vec<&str> = links.iter().flat_map(|link| [link.parent, link.child]).collect();
    frames.sort_unstable();
    frames.dedup();
    if let Some(unknown) = [child, parent].into_iter().find(|frame| !frames.contains(frame)) {
        return Err(format!(
            "frame {unknown:?} is on no transform of the topic or its static topic; the frames are: {}",
            frames.join(", ")
        ));
    }
    let up_from_child = chain_up(links, child)?;
    let up_from_parent = chain_up(links, parent)?;
    let frames_above = |chain: &[usize], start: &str| -> Vec<String> {
        std::iter::once(start.to_owned()).chain(chain.iter().map(|&l| links[l].parent.to_owned())).collect()
    };
    let above_child = frames_above(&up_from_child, child);
    let above_parent = frames_above(&up_from_parent, parent);
    let Some(common) = above_child.iter().position(|frame| above_parent.contains(frame)) else {
        let top_child = above_child.last().map_or(child, String::as_str);
        let top_parent = above_parent.last().map_or(parent, String::as_str);
        return Err(format!(
            "frames {parent:?} and {child:?} are not linked: going up, {child:?} reaches {top_child:?} and \
             {parent:?} reaches {top_parent:?}; the missing link is a transform with child {top_child:?} \
             (or {top_parent:?})"
        ));
    };
    let common_in_parent = above_parent.iter().position(|frame| frame == &above_child[common]).unwrap_or(0);
    let down_to_child: Vec<usize> = up_from_child[..common].to_vec();
    let down_to_parent: Vec<usize> = up_from_parent[..common_in_parent].to_vec();
    // The timing link: the moving link nearest to the child, else to the parent.
    let Some(&timing) = down_to_child.iter().chain(&down_to_parent).find(|&&l| !links[l].is_static) else {
        return Err(format!(
            "every transform between {parent:?} and {child:?} is static: there is no time to give the poses"
        ));
    };
    let pose_at = |chain: &[usize], stamp_ns: i64| -> Option<Isometry3<f64>> {
        // `chain` goes up from a frame; the pose of the frame in the top is the product top-down.
        chain.iter().rev().try_fold(Isometry3::identity(), |pose, &l| Some(pose * link_at(&links[l], stamp_ns)?))
    };
    let mut poses = Vec::with_capacity(links[timing].rows.len());
    for row in links[timing].rows {
        let (Some(to_child), Some(to_parent)) =
            (pose_at(&down_to_child, row.stamp_ns), pose_at(&down_to_parent, row.stamp_ns))
        else {
            continue;
        };
        let pose = to_parent.inverse() * to_child;
        let q = pose.rotation.coords;
        poses.push(Row {
            stamp_ns: row.stamp_ns,
            position: pose.translation.vector.into(),
            orientation: [q.x, q.y, q.z, q.w],
            source: row.source,
        });
    }
    if poses.is_empty() {
        let spans: Vec<String> = down_to_child
            .iter()
            .chain(&down_to_parent)
            .filter(|&&l| !links[l].is_static)
            .map(|&l| {
                let rows = links[l].rows;
                let (first, last) = (rows.first().map_or(0, |r| r.stamp_ns), rows.last().map_or(0, |r| r.stamp_ns));
                format!("{} -> {} from {first} to {last} ns", links[l].parent, links[l].child)
            })
            .collect();
        return Err(format!(
            "no stamp of {} -> {} lies within the span of every other moving transform ({})",
            links[timing].parent,
            links[timing].child,
            spans.join(", ")
        ));
    }
    Ok(poses)
}

/// The links going up from `frame` to the top of its tree, nearest first.
fn chain_up(links: &[Link<'_>], frame: &str) -> Result<Vec<usize>, String> {
    let mut chain = Vec::new();
    let mut at = frame;
    loop {
        let parents: Vec<usize> = (0..links.len()).filter(|&l| links[l].child == at).collect();
        let Some(&up) = parents.first() else { return Ok(chain) };
        if let Some(&other) = parents.iter().find(|&&l| links[l].parent != links[up].parent) {
            return Err(format!(
                "frame {at:?} has two parents, {:?} and {:?}: transforms must form a tree",
                links[up].parent, links[other].parent
            ));
        }
        // Prefer the moving link when the same pair is on both topics.
        let up = parents.iter().copied().find(|&l| !links[l].is_static).unwrap_or(up);
        if chain.contains(&up) || chain.len() > links.len() {
            return Err(format!("the transforms above frame {frame:?} form a cycle through {at:?}"));
        }
        chain.push(up);
        at = links[up].parent;
    }
}

/// The transform of `link` at `stamp_ns`: static, exact, or interpolated between the two
/// around it; `None` outside its span.
fn link_at(link: &Link<'_>, stamp_ns: i64) -> Option<Isometry3<f64>> {
    let rows = link.rows;
    if link.is_static {
        return rows.last().map(isometry);
    }
    let after = rows.partition_point(|row| row.stamp_ns < stamp_ns);
    let next = rows.get(after)?;
    if next.stamp_ns == stamp_ns {
        return Some(isometry(next));
    }
    let before = rows.get(after.checked_sub(1)?)?;
    let fraction = (stamp_ns - before.stamp_ns) as f64 / (next.stamp_ns - before.stamp_ns) as f64;
    let (a, b) = (isometry(before), isometry(next));
    let translation = a.translation.vector.lerp(&b.translation.vector, fraction);
    let rotation = a.rotation.try_slerp(&b.rotation, fraction, 1e-12).unwrap_or(a.rotation);
    Some(Isometry3::from_parts(Translation3::from(translation), rotation))
}

fn isometry(row: &Row) -> Isometry3<f64> {
    let [x, y, z, w] = row.orientation;
    let rotation = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
    Isometry3::from_parts(Translation3::from(Vector3::from(row.position)), rotation)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(stamp_ns: i64, position: [f64; 3], yaw: f64) -> Row {
        let (s, c) = (yaw / 2.0).sin_cos();
        Row {
            stamp_ns,
            position,
            orientation: [0.0, 0.0, s, c],
            source: MessageRef { file: 0, offset: 0, offset_in_chunk: None },
        }
    }

    #[test]
    fn a_chain_composes_and_interpolates_the_slower_link() {
        let map_odom = [row(0, [10.0, 0.0, 0.0], 0.0), row(10, [20.0, 0.0, 0.0], 0.0)];
        let odom_base = [row(5, [1.0, 0.0, 0.0], std::f64::consts::FRAC_PI_2)];
        let base_laser = [row(0, [0.0, 2.0, 0.0], 0.0)];
        let links = [
            Link { parent: "map", child: "odom", rows: &map_odom, is_static: false },
            Link { parent: "odom", child: "base_link", rows: &odom_base, is_static: false },
            Link { parent: "base_link", child: "laser", rows: &base_laser, is_static: true },
        ];
        let poses = compose(&links, "map", "laser").unwrap();
        assert_eq!(poses.len(), 1);
        assert_eq!(poses[0].stamp_ns, 5);
        // map->odom at t=5 is (15, 0); base_link at (16, 0) facing +y; the laser 2 m to its left.
        let p = poses[0].position;
        assert!((p[0] - 14.0).abs() < 1e-12 && (p[1] - 0.0).abs() < 1e-12, "{p:?}");
        // And the other way round: the map in the laser's frame is the inverse.
        let back = compose(&links, "laser", "map").unwrap();
        assert_eq!(back.len(), 1, "timed by odom->base_link, the moving link nearest the laser");
        let q = back[0].position;
        // The map's origin seen from the laser at (14, 0) facing +y: 14 m behind its y axis.
        assert!((q[0] - 0.0).abs() < 1e-12 && (q[1] - 14.0).abs() < 1e-12, "{q:?}");
    }

    #[test]
    fn frames_not_linked_name_the_tops_of_their_chains() {
        let rows = [row(0, [0.0; 3], 0.0)];
        let links = [
            Link { parent: "map", child: "odom", rows: &rows, is_static: false },
            Link { parent: "base_link", child: "velodyne", rows: &rows, is_static: true },
        ];
        let error = compose(&links, "map", "velodyne").unwrap_err();
        assert!(
            error.contains("\"velodyne\" reaches \"base_link\"") && error.contains("\"map\" reaches \"map\""),
            "{error}"
        );
        assert!(error.contains("missing link is a transform with child \"base_link\""), "{error}");
    }
}
