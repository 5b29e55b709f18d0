// inference/model_checksum: the integrity check of a model file against the SHA-256 digest
// stored beside it.
//
// Contract: a model `<name>.onnx` may have a checksum file `<name>.onnx.sha256` beside it, in
// sha256sum's format ("<64 hex digits>  <file name>", so `sha256sum -c` checks it too; only
// the digest is read). Engine::load() verifies the bytes it read against it: a mismatch or a
// malformed checksum file fails the load with a message naming the file, the expected and the
// actual digest. A model without a checksum file loads (models made on the fly by tests and
// training tools have none); the application's configuration reports it as a start-up warning
// (docs/inference.md). tools/detector/export.py writes the file; scripts/model_checksums.sh
// writes or checks it for existing models. Start-up only.
#pragma once

#include <string>
#include <string_view>

namespace vp::inference {

// SHA-256 (FIPS 180-4) of `bytes`, as 64 lowercase hex digits.
std::string sha256Hex(std::string_view bytes);

// The checksum file of a model: modelPath + ".sha256".
std::string checksumPath(const std::string& modelPath);

enum class ChecksumResult { Verified, NoChecksumFile, Mismatch, Malformed };

// Checks `bytes` (the content of modelPath) against the model's checksum file. On Mismatch or
// Malformed, *why says which file and what ("model.onnx: SHA-256 mismatch: expected <hex>
// (model.onnx.sha256), actual <hex>: the file is corrupt or was changed").
ChecksumResult verifyModelChecksum(const std::string& modelPath, std::string_view bytes,
                                   std::string* why);

}  // namespace vp::inference
