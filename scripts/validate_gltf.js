#!/usr/bin/env node
// Validates glTF/GLB files with the Khronos glTF validator (npm's gltf-validator, installed into the
// repository's node_modules/ by scripts/install-deps.sh from package-lock.json):
//     node scripts/validate_gltf.js FILE...
// prints each file's error, warning and info counts, every error's and warning's message, and exits
// 1 when any file has an error or a problem with extensions (one used but not required, which the
// validator itself only notes, or required but not used: a loader without it would show a wrong
// model), 2 when it cannot validate at all (the validator is not installed, a file cannot be
// read). The tests run it on every glTF and GLB they write (tests/test_mesh_gltf.cpp,
// examples/CMakeLists.txt).
const fs = require('fs');
const path = require('path');

let validator;
try {
    validator = require('gltf-validator');
} catch (e) {
    console.error(`validate_gltf.js: cannot load npm's gltf-validator (${e.code || e.message}): ` +
                  'run scripts/install-deps.sh --tests (npm ci installs it into node_modules/)');
    process.exit(2);
}

async function main() {
    const files = process.argv.slice(2);
    if (files.length === 0) {
        console.error('validate_gltf.js: no file given (usage: node scripts/validate_gltf.js FILE...)');
        process.exit(2);
    }
    let failed = false;
    for (const file of files) {
        const bytes = new Uint8Array(fs.readFileSync(file));
        const report = await validator.validateBytes(bytes, {
            uri: path.basename(file),
            externalResourceFunction: () => Promise.reject(new Error('external resources are not expected')),
        });
        const i = report.issues;
        const extensionWarnings = i.messages.filter((m) => m.severity === 1 && m.code.includes('EXTENSION'));
        // The validator only notes (as an info) an extension used but not required; krs writes no
        // fallback for any extension, so a loader without it would show a wrong model (with
        // EXT_mesh_gpu_instancing used only: each mesh once, at the origin). Counted here with the
        // validator's warnings about extensions.
        const required = report.info.extensionsRequired || [];
        for (const name of report.info.extensionsUsed || []) {
            if (!required.includes(name)) {
                extensionWarnings.push({severity: 1, code: 'KRS_EXTENSION_NOT_REQUIRED', pointer: '/extensionsRequired',
                                        message: `'${name}' is used but not required, and the file has no fallback for it`});
            }
        }
        console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings ` +
                    `(${extensionWarnings.length} about extensions), ${i.numInfos} infos`);
        for (const m of i.messages.concat(extensionWarnings.filter((w) => !i.messages.includes(w)))) {
            if (m.severity <= 1) {
                console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code}: ${m.message} (${m.pointer || ''})`);
            }
        }
        if (i.numErrors > 0 || extensionWarnings.length > 0) failed = true;
    }
    process.exit(failed ? 1 : 0);
}
main().catch((e) => { console.error(`validate_gltf.js: ${e.message || e}`); process.exit(2); });
