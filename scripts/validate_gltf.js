#!/usr/bin/env node
// Validates glTF/GLB files with the Khronos glTF validator (npm's gltf-validator):
//     NODE_PATH=<dir holding node_modules/gltf-validator> node scripts/validate_gltf.js FILE...
// prints each file's error, warning and info counts and the errors' messages, and exits 1 when
// any file has an error (tests/test_mesh_gltf.cpp runs it).
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function main() {
    let failed = false;
    for (const file of process.argv.slice(2)) {
        const bytes = new Uint8Array(fs.readFileSync(file));
        const report = await validator.validateBytes(bytes, {
            uri: path.basename(file),
            externalResourceFunction: () => Promise.reject(new Error('external resources are not expected')),
        });
        const i = report.issues;
        console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
        for (const m of i.messages) if (m.severity === 0) console.log(`  error ${m.code}: ${m.message} (${m.pointer || ''})`);
        if (i.numErrors > 0) failed = true;
    }
    process.exit(failed ? 1 : 0);
}
main().catch((e) => { console.error(e); process.exit(2); });
