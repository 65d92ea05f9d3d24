//! Every integration test of `incal-records` in one binary (one link instead of
//! one per file); each file is a module. The statistical tier runs with
//! `INCAL_TESTS=full` (see `incal::sim::tier`).

mod common;
mod concurrency;
mod drift;
mod migrations;
mod postgres;
mod store;
mod workflow;
