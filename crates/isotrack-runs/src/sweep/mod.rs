//! The sweep engine: the rows of `results.csv` ([`rows`]), a sweep read and checked
//! ([`prepared`]), run into an output directory ([`run`]), its manifest ([`manifest`]), the
//! index that `--resume` and `merge` read a results file through ([`index`], rows checked by
//! [`check`]), shards merged ([`merge`]), the output-directory lock ([`lock`]) and the worker
//! pool ([`pool`]).
//!
//! Crash safety: every finished run appends one complete line to `results.csv` (one `write` of
//! the whole line, then a flush), so a sweep killed at any moment leaves complete rows plus at
//! most one partial last line. `--resume` drops that partial line, keeps every complete row, runs
//! only the missing ids, and at the end the file is rewritten sorted by `run_id` (to a temporary
//! file, then renamed), so it is the same bit for bit whatever the thread count, the shard split
//! or the interruptions.

pub mod check;
pub mod index;
pub mod lock;
pub mod manifest;
pub mod merge;
pub mod pool;
pub mod prepared;
pub mod rows;
pub mod run;
