//! Pose errors and silhouette figures (SPEC §6). (Being written.)
