//! The tensor files of a policy directory at the byte level: raw tensors to
//! write (`Raw`, `serialize`) and a reader that checks each tensor's dtype
//! and shape and names the file in its errors (`Reader`).

use anyhow::{bail, ensure};
use safetensors::{Dtype, SafeTensors};
use std::collections::BTreeMap;
use std::path::Path;

/// One tensor to write: dtype, shape and little-endian bytes.
pub(crate) struct Raw {
    pub dtype: Dtype,
    pub shape: Vec<usize>,
    pub bytes: Vec<u8>,
}

/// Little-endian bytes of `values`, N bytes each, as one tensor of `dtype`.
fn le_raw<const N: usize, T: Copy>(dtype: Dtype, values: &[T], shape: Vec<usize>, to_le: fn(T) -> [u8; N]) -> Raw {
    Raw { dtype, shape, bytes: values.iter().flat_map(|v| to_le(*v)).collect() }
}

pub(crate) fn f32_raw(values: &[f32], shape: Vec<usize>) -> Raw {
    le_raw(Dtype::F32, values, shape, f32::to_le_bytes)
}

pub(crate) fn f64_raw(values: &[f64], shape: Vec<usize>) -> Raw {
    le_raw(Dtype::F64, values, shape, f64::to_le_bytes)
}

pub(crate) fn u64_raw(values: &[u64], shape: Vec<usize>) -> Raw {
    le_raw(Dtype::U64, values, shape, u64::to_le_bytes)
}

/// Bytes as one U8 tensor of `shape`.
pub(crate) fn u8_raw(bytes: Vec<u8>, shape: Vec<usize>) -> Raw {
    Raw { dtype: Dtype::U8, shape, bytes }
}

pub(crate) fn serialize(
    tensors: &BTreeMap<String, Raw>,
    metadata: Option<std::collections::HashMap<String, String>>,
) -> anyhow::Result<Vec<u8>> {
    let views = tensors
        .iter()
        .map(|(k, r)| Ok((k.clone(), safetensors::tensor::TensorView::new(r.dtype, r.shape.clone(), &r.bytes)?)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok(safetensors::serialize(views, metadata)?)
}

pub(crate) struct Reader<'a> {
    file: String,
    st: SafeTensors<'a>,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(file: &Path, bytes: &'a [u8]) -> anyhow::Result<Self> {
        let st = SafeTensors::deserialize(bytes)
            .map_err(|e| anyhow::anyhow!("{}: not a valid safetensors file: {e:?}", file.display()))?;
        Ok(Self { file: file.display().to_string(), st })
    }

    pub(crate) fn raw(&self, name: &str, dtype: Dtype, shape: &[usize]) -> anyhow::Result<&'a [u8]> {
        let t = self.st.tensor(name).map_err(|_| anyhow::anyhow!("{}: missing tensor {name}", self.file))?;
        ensure!(t.dtype() == dtype, "{}: tensor {name} has dtype {:?}, expected {dtype:?}", self.file, t.dtype());
        ensure!(t.shape() == shape, "{}: tensor {name} has shape {:?}, expected {shape:?}", self.file, t.shape());
        Ok(t.data())
    }

    /// A tensor of `dtype` as values of N little-endian bytes each.
    fn le_values<const N: usize, T>(
        &self,
        name: &str,
        dtype: Dtype,
        shape: &[usize],
        from_le: fn([u8; N]) -> T,
    ) -> anyhow::Result<Vec<T>> {
        let bytes = self.raw(name, dtype, shape)?;
        Ok(bytes.chunks_exact(N).map(|c| from_le(c.try_into().unwrap_or([0; N]))).collect())
    }

    pub(crate) fn f32s(&self, name: &str, shape: &[usize]) -> anyhow::Result<Vec<f32>> {
        self.le_values(name, Dtype::F32, shape, f32::from_le_bytes)
    }

    /// "{layer}.log_sigma", or ln of "{layer}.sigma" in files from before sigma was trained in log space.
    pub(crate) fn log_sigma(&self, layer: &str) -> anyhow::Result<Vec<f32>> {
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

    pub(crate) fn u32s(&self, name: &str, shape: &[usize]) -> anyhow::Result<Vec<u32>> {
        self.le_values(name, Dtype::U32, shape, u32::from_le_bytes)
    }

    pub(crate) fn f64s(&self, name: &str, shape: &[usize]) -> anyhow::Result<Vec<f64>> {
        self.le_values(name, Dtype::F64, shape, f64::from_le_bytes)
    }

    pub(crate) fn u64s(&self, name: &str, shape: &[usize]) -> anyhow::Result<Vec<u64>> {
        self.le_values(name, Dtype::U64, shape, u64::from_le_bytes)
    }

    /// The names of the file's tensors.
    pub(crate) fn names(&self) -> Vec<&str> {
        self.st.names()
    }

    pub(crate) fn shape_of(&self, name: &str) -> anyhow::Result<Vec<usize>> {
        Ok(self.st.tensor(name).map_err(|_| anyhow::anyhow!("{}: missing tensor {name}", self.file))?.shape().to_vec())
    }
}
