//! Every integration test of `incal-fuzz` in one binary (one link instead of
//! one per file); each file is a module. The statistical tier runs with
//! `INCAL_TESTS=full` (see `incal::sim::tier`).

mod fuzz_props;
mod registry;
