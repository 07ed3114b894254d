//! Checkpoint files: the full state of a run at the end of a step, to resume it bit for
//! bit ([`Simulation::snapshot`], [`Simulation::restore`]).
//!
//! Layout: a 24-byte header, then the payload.
//! - bytes 0..8: the magic `DDA-CKPT`;
//! - 8..12: the format version, u32 little-endian ([`CHECKPOINT_VERSION`]);
//! - 12..20: the payload length in bytes, u64 little-endian;
//! - 20..24: the CRC-32 (IEEE) of the payload, u32 little-endian;
//! - the payload: a [`Checkpoint`] in bincode 2's standard configuration.
//!
//! Files are written atomically: into a temporary sibling, flushed to disk (fsync),
//! renamed over the target, and the directory flushed, so a run killed at any moment
//! leaves either the previous checkpoint or the new one, whole.

use crate::scene::Scene;
use crate::simulation::{RunOptions, Simulation};
use crate::state::Snapshot;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The first eight bytes of every checkpoint file.
pub const CHECKPOINT_MAGIC: [u8; 8] = *b"DDA-CKPT";

/// The format version written; files of another version are refused. Version 2: the
/// contacts' pairs carry the cover detector's deep flag. Version 3: the physics guard's
/// energy balance and recorded violations; the engine's state as one record and the
/// running program's record apart from it. Version 4: what has come of each bolt.
/// Version 6: the iterative solver's counters. Version 7: the same record, but a scene
/// without `materials.*.damping` now damps its blocks' strain (their own), and the
/// open-close iteration settles friction forces and the average-acceleration rule's
/// shares of a step: a run begun before would go on under other mechanics. Version 8:
/// the same record, under a contact law whose sliding contacts kept from locking slide
/// back where their motion reversed, and glue whose seam ends hold past their edges'
/// ends. Version 9: the same record, but a scene without `analysis.contact_damping` now
/// damps its contacts' normal springs. Version 10: the same record, but a scene without
/// `analysis.integration` now steps by the damped rule.
pub const CHECKPOINT_VERSION: u32 = 10;

/// Length of the header before the payload.
const HEADER_LEN: usize = 24;

/// What a checkpoint file holds: the scene, the engine's state, and the bookkeeping of
/// the program that ran it (opaque here: the `dda` command keeps how far its output
/// files had got).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The scene as run (overrides applied), as JSON: validated again on resume.
    pub scene_json: String,
    /// The engine's state.
    pub engine: Snapshot,
    /// The running program's own record, as it wrote it (empty for a library user).
    pub client: String,
}

/// Why a checkpoint could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CheckpointError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file does not start with the checkpoint magic.
    #[error("{path}: not a dda checkpoint (bad magic bytes)")]
    NotACheckpoint {
        /// The file.
        path: PathBuf,
    },
    /// The file is of another format version.
    #[error(
        "{path}: checkpoint format version {found}, this dda reads version {expected} (a \
         run begun by another version goes on under other mechanics: run its scene.json \
         again)"
    )]
    Version {
        /// The file.
        path: PathBuf,
        /// Version in the file.
        found: u32,
        /// Version this build reads.
        expected: u32,
    },
    /// The file is shorter (or longer) than its header says.
    #[error("{path}: truncated checkpoint: {found} bytes of payload, the header says {expected}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// Payload bytes present.
        found: u64,
        /// Payload bytes announced.
        expected: u64,
    },
    /// The payload does not match its checksum.
    #[error("{path}: corrupted checkpoint: checksum {found:08x}, the header says {expected:08x}")]
    Checksum {
        /// The file.
        path: PathBuf,
        /// Checksum of the payload present.
        found: u32,
        /// Checksum in the header.
        expected: u32,
    },
    /// The payload could not be decoded or encoded, or does not fit its scene.
    #[error("{path}: invalid checkpoint: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

impl Checkpoint {
    /// The checkpoint of `sim`, run from `scene`, with the running program's record
    /// `client`.
    pub fn of(sim: &Simulation, scene: &Scene, client: String) -> Result<Self, String> {
        let scene_json = serde_json::to_string(scene).map_err(|e| e.to_string())?;
        Ok(Checkpoint {
            scene_json,
            engine: sim.snapshot(),
            client,
        })
    }

    /// The file's bytes: header and payload.
    pub fn to_bytes(&self) -> Result<Vec<u8>, String> {
        let payload = bincode::serde::encode_to_vec(self, bincode::config::standard())
            .map_err(|e| e.to_string())?;
        let mut out = Vec::with_capacity(HEADER_LEN + payload.len());
        out.extend_from_slice(&CHECKPOINT_MAGIC);
        out.extend_from_slice(&CHECKPOINT_VERSION.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        Ok(out)
    }

    /// Reads a checkpoint from `bytes` (the contents of `path`, named in errors),
    /// checking magic, version, length and checksum before decoding.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self, CheckpointError> {
        let path = path.to_path_buf();
        if bytes.len() < 8 || bytes[..8] != CHECKPOINT_MAGIC {
            return Err(CheckpointError::NotACheckpoint { path });
        }
        if bytes.len() < HEADER_LEN {
            return Err(CheckpointError::Truncated {
                path,
                found: 0,
                expected: 0,
            });
        }
        let word = |at: usize| {
            u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
        };
        let version = word(8);
        if version != CHECKPOINT_VERSION {
            return Err(CheckpointError::Version {
                path,
                found: version,
                expected: CHECKPOINT_VERSION,
            });
        }
        let expected = u64::from(word(12)) | (u64::from(word(16)) << 32);
        let payload = &bytes[HEADER_LEN..];
        if payload.len() as u64 != expected {
            return Err(CheckpointError::Truncated {
                path,
                found: payload.len() as u64,
                expected,
            });
        }
        let crc = word(20);
        let found = crc32fast::hash(payload);
        if found != crc {
            return Err(CheckpointError::Checksum {
                path,
                found,
                expected: crc,
            });
        }
        let (ck, used): (Checkpoint, usize) =
            bincode::serde::decode_from_slice(payload, bincode::config::standard()).map_err(
                |e| CheckpointError::Invalid {
                    path: path.clone(),
                    message: e.to_string(),
                },
            )?;
        if used != payload.len() {
            return Err(CheckpointError::Invalid {
                path,
                message: format!("{} bytes left over after the state", payload.len() - used),
            });
        }
        Ok(ck)
    }

    /// Reads the checkpoint file at `path`.
    pub fn load(path: &Path) -> Result<Self, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_bytes(&bytes, path)
    }

    /// Writes the checkpoint to `path` atomically (temporary sibling, fsync, rename,
    /// directory fsync).
    pub fn save(&self, path: &Path) -> Result<(), CheckpointError> {
        let bytes = self
            .to_bytes()
            .map_err(|message| CheckpointError::Invalid {
                path: path.to_path_buf(),
                message,
            })?;
        write_atomically(path, &bytes).map_err(|source| CheckpointError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// The scene the checkpoint was taken from.
    pub fn scene(&self, path: &Path) -> Result<Scene, CheckpointError> {
        serde_json::from_str(&self.scene_json).map_err(|e| CheckpointError::Invalid {
            path: path.to_path_buf(),
            message: format!("its scene: {e}"),
        })
    }

    /// The simulation resumed from this checkpoint, for `model` (validated from
    /// [`Checkpoint::scene`]).
    pub fn resume(
        self,
        model: crate::Model,
        options: RunOptions,
        path: &Path,
    ) -> Result<Simulation, CheckpointError> {
        Simulation::restore(model, options, self.engine).map_err(|message| {
            CheckpointError::Invalid {
                path: path.to_path_buf(),
                message,
            }
        })
    }
}

/// Writes `bytes` to `path` so that `path` holds either its old contents or all of the
/// new ones whenever the process dies: a temporary sibling, fsync, rename, directory
/// fsync. On an error the temporary sibling is removed.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "checkpoint".into());
    let tmp = path.with_file_name(format!(".{name}.tmp"));
    let written = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = written {
        // No temporary file is left behind.
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        // Makes the rename itself durable; not every platform can open a directory.
        if let Ok(d) = std::fs::File::open(dir) {
            let _ = d.sync_all();
        }
    }
    Ok(())
}
