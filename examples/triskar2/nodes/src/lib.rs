#![cfg_attr(not(test), no_std)]
//! Triskar2 nodes.
