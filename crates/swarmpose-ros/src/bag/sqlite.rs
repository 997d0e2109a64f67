//! One rosbag2 SQLite 3 file (`.db3`): the `topics` table (id, name, type,
//! serialization_format) and the `messages` table (id, topic_id, timestamp, data), through
//! `rusqlite` with its bundled SQLite (nothing to install).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use rusqlite::{Connection, OpenFlags};

use super::{Entry, Location, TopicSink};
use crate::error::RosError;

/// An indexed `.db3` file.
#[derive(Debug)]
pub(crate) struct SqliteFile {
    path: PathBuf,
    conn: Mutex<Connection>,
}

fn sql_error(path: &Path, e: &rusqlite::Error) -> RosError {
    RosError::Container {
        path: path.to_owned(),
        message: format!("not a readable rosbag2 SQLite file: {e}"),
    }
}

impl SqliteFile {
    /// Indexes `path` (file `file_no` of its bag) into `sink`.
    ///
    /// # Errors
    /// [`RosError::Container`] for a file that is not an SQLite database with the
    /// rosbag2 tables, or a message on an undefined topic.
    pub(crate) fn index(
        path: &Path,
        file_no: usize,
        sink: &mut TopicSink,
    ) -> Result<Self, RosError> {
        let err = |e: rusqlite::Error| sql_error(path, &e);
        if std::fs::metadata(path).map(|m| m.len()).unwrap_or(0) == 0 {
            return Err(RosError::Container {
                path: path.to_owned(),
                message: "empty file (0 bytes): not an SQLite bag".to_owned(),
            });
        }
        let conn = Connection::open_with_flags(
            path,
            OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
        )
        .map_err(err)?;
        let mut ids: Vec<(i64, usize)> = Vec::new();
        {
            let mut stmt = conn
                .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
                .map_err(err)?;
            let rows = stmt
                .query_map([], |r| {
                    Ok((
                        r.get::<_, i64>(0)?,
                        r.get::<_, String>(1)?,
                        r.get::<_, String>(2)?,
                        r.get::<_, String>(3)?,
                    ))
                })
                .map_err(err)?;
            for row in rows {
                let (id, name, ty, enc) = row.map_err(err)?;
                let topic =
                    sink.topic(&name, &ty, &enc)
                        .map_err(|message| RosError::Container {
                            path: path.to_owned(),
                            message,
                        })?;
                ids.push((id, topic));
            }
            let mut stmt = conn
                .prepare("SELECT id, topic_id, timestamp FROM messages ORDER BY timestamp, id")
                .map_err(err)?;
            let rows = stmt
                .query_map([], |r| {
                    Ok((
                        r.get::<_, i64>(0)?,
                        r.get::<_, i64>(1)?,
                        r.get::<_, i64>(2)?,
                    ))
                })
                .map_err(err)?;
            for row in rows {
                let (id, topic_id, stamp) = row.map_err(err)?;
                let topic = ids
                    .iter()
                    .find(|t| t.0 == topic_id)
                    .map(|t| t.1)
                    .ok_or_else(|| RosError::Container {
                        path: path.to_owned(),
                        message: format!(
                            "message {id} is on topic id {topic_id}, not in the topics table"
                        ),
                    })?;
                sink.push(
                    topic,
                    Entry {
                        log_time_ns: stamp,
                        location: Location::Sqlite { file: file_no, id },
                    },
                );
            }
        }
        Ok(Self {
            path: path.to_owned(),
            conn: Mutex::new(conn),
        })
    }

    /// The data of the message at `location`.
    ///
    /// # Errors
    /// [`RosError::Container`] when the row cannot be read.
    pub(crate) fn read(&self, location: Location) -> Result<Vec<u8>, RosError> {
        let Location::Sqlite { id, .. } = location else {
            return Err(RosError::Container {
                path: self.path.clone(),
                message: "an MCAP record asked of an SQLite file".to_owned(),
            });
        };
        let conn = self.conn.lock().map_err(|_| RosError::Container {
            path: self.path.clone(),
            message: "connection poisoned".to_owned(),
        })?;
        conn.query_row("SELECT data FROM messages WHERE id = ?1", [id], |r| {
            r.get::<_, Vec<u8>>(0)
        })
        .map_err(|e| sql_error(&self.path, &e))
    }
}
