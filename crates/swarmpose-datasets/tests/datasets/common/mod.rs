//! Shared helpers of the dataset tests.

use std::path::PathBuf;

/// The directory of a shared data set (see [`swarmpose_testdata::dataset_for_test`]).
pub fn dataset(name: &str) -> Option<PathBuf> {
    swarmpose_testdata::dataset_for_test(name)
}
