//! Which file a parsed XML document came from, for documents read from other files
//! than the one being loaded (MJCF `<include>`s): an error at one of their elements
//! names that file. A thread-local registry, alive while the including file is read.

use roxmltree::Document;
use std::cell::RefCell;
use std::path::PathBuf;

thread_local! {
    /// The included documents being read on this thread (by address) and their
    /// files, so that an error at one of their elements names the right file.
    static FILES: RefCell<Vec<(usize, PathBuf)>> = const { RefCell::new(Vec::new()) };
}

/// While alive, errors at elements of the registered documents name their files.
pub(crate) struct Registered(usize);

impl Drop for Registered {
    fn drop(&mut self) {
        FILES.with(|f| f.borrow_mut().truncate(self.0));
    }
}

/// Register the included documents (`docs[k]` read from `texts[k].0`).
pub(crate) fn register(docs: &[Document], texts: &[(PathBuf, String)]) -> Registered {
    FILES.with(|f| {
        let mut f = f.borrow_mut();
        let before = f.len();
        for (d, (path, _)) in docs.iter().zip(texts) {
            f.push((d as *const Document as usize, path.clone()));
        }
        Registered(before)
    })
}

/// The file an element's document was included from, if it was.
pub(crate) fn file_of(doc: &Document) -> Option<PathBuf> {
    let at = doc as *const Document as usize;
    FILES.with(|f| {
        f.borrow()
            .iter()
            .find(|(d, _)| *d == at)
            .map(|(_, p)| p.clone())
    })
}
