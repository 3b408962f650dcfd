#!/usr/bin/env node
// Validates glTF files with the Khronos glTF validator (npm package `gltf-validator`, a JS library: its
// validateBytes() gives a report with issues.numErrors and the messages). Usage: node validate_gltf.js FILE...
// Prints one summary line per file and every error; exit 0 when no file has an error, 1 otherwise, and 77 when the
// validator is not installed (`npm install -g gltf-validator`; cmake/install-deps.sh installs it).
'use strict';
const fs = require('fs');
const path = require('path');
const { execSync } = require('child_process');

function loadValidator() {
    try {
        return require('gltf-validator');
    } catch (e) {
        // A global install is not on node's search path unless NODE_PATH says so: ask npm where it is.
    }
    try {
        const root = execSync('npm root -g', { encoding: 'utf8', stdio: ['ignore', 'pipe', 'ignore'] }).trim();
        return require(path.join(root, 'gltf-validator'));
    } catch (e) {
        return null;
    }
}

async function main(files) {
    const validator = loadValidator();
    if (!validator) {
        console.log('gltf-validator is not installed (npm install -g gltf-validator)');
        return 77;
    }
    console.log(`glTF validator ${validator.version()}`);
    let failed = 0;
    for (const file of files) {
        let report;
        try {
            report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), { uri: file, maxIssues: 0 });
        } catch (e) {
            console.log(`${file}: not validated: ${e}`);
            ++failed;
            continue;
        }
        const i = report.issues;
        console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
        for (const m of i.messages) {
            if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer || '-'}: ${m.message}`);
        }
        if (i.numErrors > 0) ++failed;
    }
    return failed > 0 ? 1 : 0;
}

if (process.argv.length < 3) {
    console.log('usage: node validate_gltf.js FILE...');
    process.exit(2);
}
main(process.argv.slice(2)).then((code) => process.exit(code));
