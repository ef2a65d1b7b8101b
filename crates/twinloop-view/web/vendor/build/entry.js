// Entry of the vendored bundle: everything the viewer page uses, as one global.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { STLLoader } from 'three/examples/jsm/loaders/STLLoader.js';
import { OBJLoader } from 'three/examples/jsm/loaders/OBJLoader.js';
import { ColladaLoader } from 'three/examples/jsm/loaders/ColladaLoader.js';
import URDFLoader from 'urdf-loader';
import uPlot from 'uplot';
window.TL = { THREE, OrbitControls, STLLoader, OBJLoader, ColladaLoader, URDFLoader, uPlot };
