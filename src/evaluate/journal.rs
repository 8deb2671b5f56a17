//! The evaluation's records on disk: one JSON line per finished piece of work, appended and
//! flushed as it finishes, so that an interrupted run loses at most the piece it was doing and
//! a second run with the same settings takes up where it stopped.

use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::error::{Error, Result};

/// Records by key, read from and appended to a JSON-lines file. Shared by threads (`&self`
/// throughout): each record is one line written under a lock.
pub struct Journal {
    path: PathBuf,
    inner: Mutex<Inner>,
}

struct Inner {
    file: File,
    records: HashMap<String, serde_json::Value>,
}

impl Journal {
    /// Opens (or creates) the journal at `path`. A last line cut short by an interrupted write
    /// is dropped (and cut from the file); any other line that is not a record is an error.
    ///
    /// # Errors
    /// A file that cannot be read or written, or a line that is not a record (naming the line).
    pub fn open(path: &Path) -> Result<Self> {
        Self::open_with(path, &[])
    }

    /// [`Journal::open`] at `path`, with the records of the complete lines of the journals
    /// `also` (other machines' shards of the same run) read too; appends go to `path` alone.
    ///
    /// # Errors
    /// As [`Journal::open`], for any of the files.
    pub fn open_with(path: &Path, also: &[PathBuf]) -> Result<Self> {
        let mut records = HashMap::new();
        for other in also {
            read_records(other, &mut records)?;
        }
        let unfinished = read_records(path, &mut records)?;
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(Error::io("open", path))?;
        if let Some(complete) = unfinished {
            file.set_len(complete as u64)
                .map_err(Error::io("truncate", path))?;
        }
        Ok(Self {
            path: path.to_path_buf(),
            inner: Mutex::new(Inner { file, records }),
        })
    }

    /// The records and the file, locked (a thread that panicked holding them left them whole:
    /// each write is one line).
    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The record under `key`, if there is one.
    ///
    /// # Errors
    /// A record that is not a `T` (a journal of another version).
    pub fn get<T: DeserializeOwned>(&self, key: &str) -> Result<Option<T>> {
        self.lock()
            .records
            .get(key)
            .map(|value| {
                T::deserialize(value).map_err(|e| Error::Evaluate {
                    problem: format!("{}: record {key:?}: {e}", self.path.display()),
                })
            })
            .transpose()
    }

    /// Appends `value` under `key`, flushes it to disk, and returns it as the journal holds
    /// it: read back, as a resumed run reads it (a pose goes through its matrix), so that a
    /// run gives the same bytes resumed or not.
    ///
    /// # Errors
    /// A value that cannot be serialised or read back, or a failed write.
    pub fn put<T: Serialize + DeserializeOwned>(&self, key: &str, value: &T) -> Result<T> {
        let value =
            serde_json::to_value(value).map_err(Error::json("write", "record", &self.path))?;
        let read_back =
            T::deserialize(&value).map_err(Error::json("read back", "record", &self.path))?;
        let line = serde_json::json!({ "key": key, "value": value });
        let mut inner = self.lock();
        writeln!(inner.file, "{line}").map_err(Error::io("write", &self.path))?;
        inner
            .file
            .sync_data()
            .map_err(Error::io("write", &self.path))?;
        inner.records.insert(key.to_string(), value);
        Ok(read_back)
    }
}

/// Reads the records of `path`'s complete lines into `records` (none when there is no file);
/// the length of those lines when an unfinished write follows them.
fn read_records(
    path: &Path,
    records: &mut HashMap<String, serde_json::Value>,
) -> Result<Option<usize>> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(Error::io("read", path)(e)),
    };
    // Everything after the last newline is an unfinished write.
    let complete = text.rfind('\n').map_or(0, |i| i + 1);
    for (number, line) in text[..complete].lines().enumerate() {
        let parsed: serde_json::Value =
            serde_json::from_str(line).map_err(|e| Error::Evaluate {
                problem: format!(
                    "{}:{}: not a record: {}",
                    path.display(),
                    number + 1,
                    mvgrasp_geometry::one_line(&e.to_string())
                ),
            })?;
        let (Some(key), Some(value)) = (parsed["key"].as_str(), parsed.get("value")) else {
            return Err(Error::Evaluate {
                problem: format!(
                    "{}:{}: a record needs \"key\" and \"value\"",
                    path.display(),
                    number + 1
                ),
            });
        };
        records.insert(key.to_string(), value.clone());
    }
    Ok((complete < text.len()).then_some(complete))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_survive_a_reopen_and_a_cut_last_line_is_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("records.jsonl");
        let journal = Journal::open(&path).unwrap();
        journal.put("a", &1u32).unwrap();
        journal.put("b", &vec![2u32, 3]).unwrap();
        drop(journal);
        // An interrupted write.
        let mut file = OpenOptions::new().append(true).open(&path).unwrap();
        write!(file, "{{\"key\":\"c\",\"val").unwrap();
        drop(file);
        let journal = Journal::open(&path).unwrap();
        assert_eq!(journal.get::<u32>("a").unwrap(), Some(1));
        assert_eq!(journal.get::<Vec<u32>>("b").unwrap(), Some(vec![2, 3]));
        assert_eq!(journal.get::<u32>("c").unwrap(), None);
        journal.put("c", &4u32).unwrap();
        drop(journal);
        let journal = Journal::open(&path).unwrap();
        assert_eq!(journal.get::<u32>("c").unwrap(), Some(4));
        assert!(journal.get::<String>("a").is_err());
    }

    #[test]
    fn a_broken_line_in_the_middle_is_an_error_naming_the_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("records.jsonl");
        std::fs::write(
            &path,
            "{\"key\":\"a\",\"value\":1}\nnot json\n{\"key\":\"b\",\"value\":2}\n",
        )
        .unwrap();
        let message = Journal::open(&path).err().unwrap().to_string();
        assert!(message.contains("records.jsonl:2"), "{message}");
    }
}
