//! Per-node tables the simulator owns at run time (from a plan or built by hand) and
//! lends to the engines as `NodeTables`, as firmware lends its generated constants. The
//! type is the model's: one definition of a module's tables for codegen and simulator.
pub use rtcan_model::ModuleTables as OwnedTables;
