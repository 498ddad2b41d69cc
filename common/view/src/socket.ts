// The page's WebSocket to its app: binary messages are state frames, text messages JSON;
// reconnects after a drop (bounded back-off).

export interface SocketHandlers {
  onFrame(data: ArrayBuffer): void;
  onText?(message: any): void;
  onStatus?(open: boolean): void;
}

export class AppSocket {
  private ws: WebSocket | null = null;
  private delayMs = 250;
  closed = false;

  constructor(private readonly url: string, private readonly handlers: SocketHandlers) {
    this.connect();
  }

  send(text: string): boolean {
    if (!this.ws || this.ws.readyState !== WebSocket.OPEN) return false;
    this.ws.send(text);
    return true;
  }

  private connect(): void {
    const ws = new WebSocket(this.url);
    ws.binaryType = 'arraybuffer';
    ws.onopen = () => { this.delayMs = 250; this.handlers.onStatus?.(true); };
    ws.onmessage = (e: MessageEvent) => {
      if (typeof e.data === 'string') {
        try {
          this.handlers.onText?.(JSON.parse(e.data));
        } catch (err) {
          console.warn('view: bad text message', err);
        }
      } else {
        this.handlers.onFrame(e.data as ArrayBuffer);
      }
    };
    ws.onclose = () => {
      this.handlers.onStatus?.(false);
      if (this.closed) return;
      setTimeout(() => this.connect(), this.delayMs);
      this.delayMs = Math.min(this.delayMs * 2, 4000);
    };
    this.ws = ws;
  }
}

export function socketUrl(path = '/ws'): string {
  const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
  return `${scheme}//${location.host}${path}`;
}
