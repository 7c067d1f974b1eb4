//! A fleet store's folder: what is written reads back as the same store (sessions, tiles bit
//! for bit, settings, poses), its tables hold the store's answer, and a refused update leaves
//! every file as it was.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use loops_core::{
    SampleSize, Sampler, SamplerKind, Trajectory, UrbanDrive, UrbanFleet,
    store::{FleetStore, StoreSession, StoreSettings},
};
use loops_io::store::{StoreConfig, read_samples, read_store, update_store};

fn sessions() -> Vec<(String, Trajectory)> {
    let spec = UrbanFleet {
        vehicles: 2,
        days: 2,
        drive: UrbanDrive { duration_s: 40.0, rate_hz: 4.0, city_size_m: 300.0, seed: 9, ..UrbanDrive::default() },
        start_spread_s: 600.0,
    };
    let fleet = spec.generate().unwrap();
    (0..fleet.len()).map(|k| (fleet.names()[k].clone(), fleet.session(k).clone())).collect()
}

fn config() -> StoreConfig {
    StoreConfig {
        settings: StoreSettings { block: 50, ..StoreSettings::new(8.0) },
        sampler: Some((Sampler::new(SamplerKind::Rho, SampleSize::Budget(20), 3), false)),
    }
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("loops-io-store-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                out.insert(path.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

#[test]
fn a_store_reads_back_as_written() {
    let dir = temp("round-trip");
    let all = sessions();
    let (day0, day1): (Vec<_>, Vec<_>) = all.iter().cloned().partition(|(n, _)| n.ends_with("day0"));
    update_store(&dir, Some(&config()), day0.clone(), &[]).unwrap();
    let report = update_store(&dir, None, day1.clone(), &[]).unwrap();
    assert_eq!(report.stored.state, "state-000002");
    let names = |d: &Path| {
        let mut n: Vec<String> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        n.sort();
        n
    };
    assert_eq!(names(&dir), ["loops-store.json", "state-000002", "store.json"], "the old state is removed");
    let read = read_store(&dir).unwrap();
    assert_eq!(read.config, config());
    assert_eq!(read.store, report.stored.store);
    // The same store as one made in memory.
    let by_name: BTreeMap<String, Trajectory> = all.iter().cloned().collect();
    let mut source = |s: &StoreSession| Ok(by_name[&s.name].clone());
    let mut memory = FleetStore::new(config().settings).unwrap();
    memory.update(all.clone(), &[], &mut source).unwrap();
    assert!(memory.tiles() == read.store.tiles());
    assert_eq!(memory.sessions(), read.store.sessions());
    // Poses read back exactly (the fingerprint is checked on reading).
    for s in read.store.sessions() {
        assert_eq!(read.poses(s).unwrap(), by_name[&s.name], "{}", s.name);
    }
    // The components table holds the store's components.
    let loops = memory.loops().unwrap();
    let rows = parquet_rows(&read.table("components.parquet"));
    assert_eq!(rows, loops.components().len());
    assert_eq!(parquet_rows(&read.table("loop_duration.parquet")), all.iter().map(|(_, t)| t.len()).sum::<usize>());
    let drawn = &report.samples.as_ref().unwrap().rows;
    assert!(!drawn.is_empty());
    assert_eq!(parquet_rows(&read.table("samples.parquet")), drawn.len());
    // Read back as drawn, and as drawn in memory.
    assert_eq!(&read_samples(&read).unwrap(), drawn);
    let (sampler, between_only) = config().sampler.unwrap();
    assert_eq!(&memory.samples(&loops, &sampler, between_only, &mut source).unwrap().rows, drawn);
    assert_eq!(report.added_components, read.store.added_components(&loops).len());
    let _ = std::fs::remove_dir_all(&dir);
}

fn parquet_rows(path: &Path) -> usize {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    let reader = SerializedFileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    reader.metadata().file_metadata().num_rows() as usize
}

#[test]
fn a_refused_update_changes_no_file() {
    let dir = temp("refused");
    let all = sessions();
    update_store(&dir, Some(&config()), all[..2].to_vec(), &[]).unwrap();
    let before = snapshot(&dir);
    let name = all[0].0.clone();
    let err = update_store(&dir, None, vec![all[0].clone()], std::slice::from_ref(&name)).unwrap_err().to_string();
    assert!(err.contains("is both given and removed"), "{err}");
    let other = StoreConfig { settings: StoreSettings { gamma: 9.0, ..config().settings }, ..config() };
    let err = update_store(&dir, Some(&other), vec![all[2].clone()], &[]).unwrap_err().to_string();
    assert!(err.contains("gamma is 8 in the store, not 9"), "{err}");
    assert_eq!(snapshot(&dir), before);
    // A file of the user's in the folder is left alone; a folder of theirs is not made a store.
    let theirs = temp("theirs");
    std::fs::create_dir_all(&theirs).unwrap();
    std::fs::write(theirs.join("notes.txt"), "mine").unwrap();
    assert!(update_store(&theirs, Some(&config()), all[..1].to_vec(), &[]).is_err());
    assert_eq!(std::fs::read_to_string(theirs.join("notes.txt")).unwrap(), "mine");
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&theirs);
}
