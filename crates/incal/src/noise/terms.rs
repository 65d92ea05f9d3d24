//! IEEE terms (todo)
