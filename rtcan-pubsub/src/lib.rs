#![cfg_attr(not(test), no_std)]
//! R2P publish/subscribe middleware.
