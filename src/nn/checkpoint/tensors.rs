//! The tensor files of a policy directory at the byte level: raw tensors to
//! write (`Raw`, `serialize`) and a reader that checks each tensor's dtype
//! and shape and names the file in its errors (`Reader`).

use anyhow::{bail, ensure};
use safetensors::{Dtype, SafeTensors};
use std::collections::BTreeMap;
use std::path::Path;

/// One tensor to write: dtype, shape and little-endian bytes.
pub(super) struct Raw {
    pub dtype: Dtype,
    pub shape: Vec<usize>,
    pub bytes: Vec<u8>,
}

pub(super) fn f32_raw(values: &[f32], shape: Vec<usize>) -> Raw {
    Raw { dtype: Dtype::F32, shape, bytes: values.iter().flat_map(|v| v.to_le_bytes()).collect() }
}

pub(super) fn serialize(
    tensors: &BTreeMap<String, Raw>,
    metadata: Option<std::collections::HashMap<String, String>>,
) -> anyhow::Result<Vec<u8>> {
    let views = tensors
        .iter()
        .map(|(k, r)| Ok((k.clone(), safetensors::tensor::TensorView::new(r.dtype, r.shape.clone(), &r.bytes)?)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok(safetensors::serialize(views, metadata)?)
}

pub(super) struct Reader<'a> {
    file: String,
    st: SafeTensors<'a>,
}

impl<'a> Reader<'a> {
    pub(super) fn new(file: &Path, bytes: &'a [u8]) -> anyhow::Result<Self> {
        let st = SafeTensors::deserialize(bytes)
            .map_err(|e| anyhow::anyhow!("{}: not a valid safetensors file: {e:?}", file.display()))?;
        Ok(Self { file: file.display().to_string(), st })
    }

    pub(super) fn raw(&self, name: &str, dtype: Dtype, shape: &[usize]) -> anyhow::Result<&'a [u8]> {
        let t = self.st.tensor(name).map_err(|_| anyhow::anyhow!("{}: missing tensor {name}", self.file))?;
        ensure!(t.dtype() == dtype, "{}: tensor {name} has dtype {:?}, expected {dtype:?}", self.file, t.dtype());
        ensure!(t.shape() == shape, "{}: tensor {name} has shape {:?}, expected {shape:?}", self.file, t.shape());
        Ok(t.data())
    }

    pub(super) fn f32s(&self, name: &str, shape: &[usize]) -> anyhow::Result<Vec<f32>> {
        Ok(self
            .raw(name, Dtype::F32, shape)?
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }

    /// "{layer}.log_sigma", or ln of "{layer}.sigma" in files from before sigma was trained in log space.
    pub(super) fn log_sigma(&self, layer: &str) -> anyhow::Result<Vec<f32>> {
        let name = format!("{layer}.log_sigma");
        if self.st.tensor(&name).is_ok() {
            return self.f32s(&name, &[1]);
        }
        let legacy = format!("{layer}.sigma");
        if self.st.tensor(&legacy).is_err() {
            bail!("{}: missing tensor {name}", self.file);
        }
        let sigma = self.f32s(&legacy, &[1])?;
        ensure!(sigma.iter().all(|s| *s > 0.0), "{}: tensor {legacy} = {sigma:?}, expected a sigma > 0", self.file);
        Ok(sigma.iter().map(|s| s.ln()).collect())
    }

    pub(super) fn u32s(&self, name: &str, shape: &[usize]) -> anyhow::Result<Vec<u32>> {
        Ok(self
            .raw(name, Dtype::U32, shape)?
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }

    pub(super) fn shape_of(&self, name: &str) -> anyhow::Result<Vec<usize>> {
        Ok(self.st.tensor(name).map_err(|_| anyhow::anyhow!("{}: missing tensor {name}", self.file))?.shape().to_vec())
    }
}
